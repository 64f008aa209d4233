// What the automatic choices of the near-field correction weigh against each other: the cost of
// a hemicube row on the GL device, and the CPU's speed at the analytic work (the far field's
// candidates and rules, exact visibility's point evaluations). `--far-field auto` turns the far
// field on where its estimated CPU cost per row is at most 30% of a hemicube row's, and
// `--exact-visibility auto` spends at most 4 × the hemicubes it spares (accuracy/near_field.hpp):
// both compare CPU work with drawing, so both move when a pixel gets cheaper (a GPU) or the CPU
// faster.
//
// `--method auto` weighs a row's cost by each engine (pipeline/row_engine.hpp, row_cost_ns): a
// hemicube row costs pixels and pieces, a ray-cast row its rays; piece_ns and ray_ns price them.
//
// The built-in values were measured on the development machines (llvmpipe on 2 cores, 5 ns per
// pixel at N = 256; docs/benchmarks.md). `ffcube calibrate` measures them on another machine and
// writes a file that `--cost-model FILE` reads (docs/accuracy.md, "Cost model"). Nothing is timed
// during a run: a file's values are inputs like any option, so the same input gives the same
// output, and a .ffm or checkpoint made with a cost model records its values.
#pragma once

#include <string>

namespace ffcube {

struct CostModel {
    // Wall nanoseconds per hemicube pixel of one worker, everything of a row included (drawing,
    // readback, accumulation; a row has 3N² pixels). Built-in: llvmpipe on these machines.
    double pixel_ns = 5.0;
    // The CPU's time at the analytic work against the development machine's (1: the same; 0.5:
    // twice as fast). Divides the budgets, which are in the development machine's nanoseconds.
    double cpu_scale = 1.0;
    // Wall nanoseconds per piece per hemicube of one worker beyond its pixels (culling, the
    // draw's set-up): a hemicube row of P pieces costs 3N² × pixel_ns + P × piece_ns. Built-in:
    // the 22,881-facet city on llvmpipe, 12 ms a hemicube at N = 128 less its 0.25 ms of pixels,
    // over 22,881 pieces: about 500 ns (docs/benchmarks.md, "Rays in coherent packets").
    double piece_ns = 500.0;
    // CPU nanoseconds per ray of one thread (the rays alone: both engines' rows are corrected alike).
    // Built-in: 56–64 ns a ray on the 5,000- and 22,881-facet cities (same section): 60 ns.
    double ray_ns = 60.0;
    // The file the values were read from; empty: the built-in values.
    std::string source;

    bool builtin() const { return source.empty(); }
};

// The ranges read_cost_model and validate(RowOptions) accept: pixel_ns within [1e-4, 1e4] ns,
// cpu_scale within [1e-3, 1e3], piece_ns within [1e-3, 1e7] ns, ray_ns within [1e-2, 1e6] ns
// (outside, a measurement went wrong).
void check_cost_model(const CostModel& m, const std::string& where);

// Reads a file written by write_cost_model (JSON: "pixel_ns", "cpu_scale", "piece_ns", "ray_ns";
// other keys are descriptive and ignored). A file from before `--method auto` followed the costs
// has no "piece_ns" or "ray_ns": the built-in values stand in for them. InputError naming the file
// and the key for a missing file, bad JSON, a missing pixel_ns or cpu_scale, a non-numeric key,
// or a value out of range.
CostModel read_cost_model(const std::string& path);

// Writes `m` (and what it was measured on, for the reader) atomically.
void write_cost_model(const std::string& path, const CostModel& m, const std::string& measured_on, int resolution,
                      double cpu_seconds, double reference_cpu_seconds);

}  // namespace ffcube
