// Jacobi and Gauss–Seidel split into row blocks (solver/row_blocks.hpp), as `mpirun … ffcube
// solve` runs them, here with one thread per block and a barrier for the exchange (no MPI): each
// block asks only for its rows; Jacobi gives the one-process iterates bit for bit; Gauss–Seidel
// (Jacobi between blocks) converges to the same solution within the bound of its residual.
#include <gtest/gtest.h>

#include <barrier>
#include <cmath>
#include <thread>

#include "ffcube/core/error.hpp"
#include "ffcube/solver/solver.hpp"
#include "fixtures.hpp"

namespace ffcube {
namespace {

using namespace ffcube::test;

// K blocks in K threads of one process; the exchange goes through shared buffers between barriers.
struct Shared {
    explicit Shared(std::vector<std::uint32_t> b)
        : bounds(std::move(b)), sync(static_cast<std::ptrdiff_t>(bounds.size() - 1)), x(bounds.back()),
          parts(bounds.size() - 1) {}
    std::vector<std::uint32_t> bounds;
    std::barrier<> sync;
    std::vector<double> x;
    std::vector<std::vector<double>> parts;
};

class ThreadRowBlocks final : public RowBlocks {
public:
    ThreadRowBlocks(Shared& s, std::size_t rank) : s_(s), r_(rank) {}
    std::uint32_t first() const override { return s_.bounds[r_]; }
    std::uint32_t last() const override { return s_.bounds[r_ + 1]; }
    void share(std::span<double> x) override {
        std::copy(x.begin() + first(), x.begin() + last(), s_.x.begin() + first());
        s_.sync.arrive_and_wait();
        std::copy(s_.x.begin(), s_.x.end(), x.begin());
        s_.sync.arrive_and_wait();
    }
    void sum(std::span<double> v) override {
        reduce(v, [](double a, double b) { return a + b; }, 0.0);
    }
    void max(std::span<double> v) override {
        reduce(v, [](double a, double b) { return std::max(a, b); }, -INFINITY);
    }

private:
    template <class Op>
    void reduce(std::span<double> v, Op op, double start) {
        s_.parts[r_].assign(v.begin(), v.end());
        s_.sync.arrive_and_wait();
        for (std::size_t k = 0; k < v.size(); ++k) {
            double a = start;
            for (const auto& p : s_.parts) a = op(a, p[k]);  // in block order, the same on every block
            v[k] = a;
        }
        s_.sync.arrive_and_wait();
    }
    Shared& s_;
    std::size_t r_;
};

struct Case {
    RandomScene rs;
    Scene scene;
};
Case mixed_case() {
    Case c{random_reciprocal(24, 0.97, 42), {}};
    std::vector<std::uint32_t> mat(24);
    for (std::uint32_t i = 0; i < mat.size(); ++i) mat[i] = i % 3;
    mat[3] = 3;
    mat[20] = 4;
    c.scene = make_scene(c.rs.areas,
                         {Material{"a", Vec3(0.8, 0.5, 0.3), Vec3(0.0)}, Material{"b", Vec3(0.6, 0.7, 0.9), Vec3(0.0)},
                          Material{"c", Vec3(0.9), Vec3(0.0)}, Material{"lamp", Vec3(0.4), Vec3(5, 4, 3)},
                          Material{"lamp2", Vec3(0.2, 0.0, 0.6), Vec3(1, 2, 3)}},
                         mat);
    return c;
}

// Solves on every block at once; returns each block's result and the rows each block asked for.
std::vector<SolveResult> solve_in_blocks(const Case& c, SolverOptions o, const std::vector<std::uint32_t>& bounds,
                                         std::vector<std::uint64_t>& requests) {
    Shared shared(bounds);
    const std::size_t k = bounds.size() - 1;
    std::vector<SolveResult> results(k);
    requests.assign(k, 0);
    std::vector<std::thread> threads;
    for (std::size_t r = 0; r < k; ++r)
        threads.emplace_back([&, r] {
            ExactRowProvider provider(c.rs.rows);
            ThreadRowBlocks blocks(shared, r);
            SolverOptions mine = o;
            mine.blocks = &blocks;
            results[r] = solve_radiosity(c.scene, provider, mine);
            requests[r] = provider.total_requests();
        });
    for (std::thread& t : threads) t.join();
    return results;
}

const std::vector<std::vector<std::uint32_t>> kSplits = {{0, 24}, {0, 12, 24}, {0, 5, 5, 17, 24}, {0, 1, 2, 3, 24}};

TEST(RowBlocks, JacobiInBlocksIsJacobi) {
    const Case c = mixed_case();
    SolverOptions o;
    o.method = SolverMethod::Jacobi;
    o.tolerance = 1e-12;
    ExactRowProvider whole(c.rs.rows);
    const SolveResult one = solve_radiosity(c.scene, whole, o);
    ASSERT_EQ(one.stop, StopReason::Converged);
    for (const auto& bounds : kSplits) {
        std::vector<std::uint64_t> requests;
        const std::vector<SolveResult> parts = solve_in_blocks(c, o, bounds, requests);
        for (std::size_t r = 0; r < parts.size(); ++r) {
            EXPECT_EQ(requests[r], bounds[r + 1] - bounds[r]) << "each block asks for its own rows only";
            EXPECT_EQ(parts[r].stop, StopReason::Converged);
            // Every row is updated from the same x by the same arithmetic as in one process, so the
            // iterates are the same bits; only the residual's summation order differs, which could
            // move the stop by a sweep only if the fraction sat within rounding of the tolerance.
            EXPECT_EQ(parts[r].iterations, one.iterations);
            for (std::size_t i = 0; i < one.radiosity.size(); ++i) EXPECT_EQ(parts[r].radiosity[i], one.radiosity[i]);
            // Sums over blocks in another order than one process: rounding only (24 terms of one sign
            // in turnover; the relative error's 1e-12 is far above 24ε).
            EXPECT_NEAR(parts[r].energy.relative_error, one.energy.relative_error, 1e-12);
            EXPECT_EQ(parts[r].stiffness.max_row_sum, one.stiffness.max_row_sum);
        }
    }
}

TEST(RowBlocks, GaussSeidelInBlocksConvergesToTheSameSolution) {
    const Case c = mixed_case();
    SolverOptions o;
    o.tolerance = 1e-12;
    o.method = SolverMethod::Direct;
    ExactRowProvider whole(c.rs.rows);
    const std::vector<Vec3> exact = solve_radiosity(c.scene, whole, o).radiosity;
    o.method = SolverMethod::GaussSeidel;
    // As in Methods.AllFourAgreeOnTheSameRows: any B whose residual is within τ × emitted satisfies
    // |B − B*|_∞ ≤ τ × emitted / A_min / (1 − q), q = max ρ × max row sum; plus rounding (24 terms).
    double q = 0.0, a_min = INFINITY, emitted = 0.0;
    for (std::size_t i = 0; i < c.scene.size(); ++i) {
        const Material& m = c.scene.materials[c.scene.patches[i].material];
        const double s = c.rs.rows[i].sum();
        q = std::max({q, m.kd.x * s, m.kd.y * s, m.kd.z * s});
        a_min = std::min(a_min, c.scene.patches[i].area);
        emitted += (m.ke.x + m.ke.y + m.ke.z) * c.scene.patches[i].area;
    }
    const double bound = o.tolerance * emitted / a_min / (1 - q) + 24 * 1.1102230246251565e-16 * max_abs(exact);
    for (const auto& bounds : kSplits) {
        std::vector<std::uint64_t> requests;
        const std::vector<SolveResult> parts = solve_in_blocks(c, o, bounds, requests);
        for (std::size_t r = 0; r < parts.size(); ++r) {
            ASSERT_EQ(parts[r].stop, StopReason::Converged);
            EXPECT_LE(max_abs_diff(parts[r].radiosity, exact), bound);
            for (std::size_t i = 0; i < exact.size(); ++i) EXPECT_EQ(parts[r].radiosity[i], parts[0].radiosity[i]);
        }
    }
}

TEST(RowBlocks, OnlyGatheringMethodsSplit) {
    const Case c = mixed_case();
    Shared shared({0, 24});
    ThreadRowBlocks blocks(shared, 0);
    for (SolverMethod m : {SolverMethod::Shoot, SolverMethod::Direct}) {
        SolverOptions o;
        o.method = m;
        o.blocks = &blocks;
        ExactRowProvider provider(c.rs.rows);
        EXPECT_THROW(solve_radiosity(c.scene, provider, o), InputError) << to_string(m);
    }
}

}  // namespace
}  // namespace ffcube
