// What the automatic choices of the near-field correction weigh against each other: the cost of
// a hemicube row on the GL device, and the CPU's speed at the analytic work (the far field's
// candidates and rules, exact visibility's point evaluations). `--far-field auto` turns the far
// field on where its estimated CPU cost per row is at most 30% of a hemicube row's, and
// `--exact-visibility auto` spends at most 4 × the hemicubes it spares (accuracy/near_field.hpp):
// both compare CPU work with drawing, so both move when a pixel gets cheaper (a GPU) or the CPU
// faster.
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
    // The file the values were read from; empty: the built-in values.
    std::string source;

    bool builtin() const { return source.empty(); }
};

// The ranges read_cost_model and validate(RowOptions) accept: pixel_ns within [1e-4, 1e4] ns,
// cpu_scale within [1e-3, 1e3] (outside, a measurement went wrong).
void check_cost_model(const CostModel& m, const std::string& where);

// Reads a file written by write_cost_model (JSON: "pixel_ns", "cpu_scale"; other keys are
// descriptive and ignored). InputError naming the file and the key for a missing file, bad JSON,
// a missing or non-numeric key, or a value out of range.
CostModel read_cost_model(const std::string& path);

// Writes `m` (and what it was measured on, for the reader) atomically.
void write_cost_model(const std::string& path, const CostModel& m, const std::string& measured_on, int resolution,
                      double cpu_seconds, double reference_cpu_seconds);

}  // namespace ffcube
