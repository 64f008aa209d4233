// A fixed set of worker threads that compute rows and hand them to the caller in the order
// asked, whichever worker finished first: the output never depends on the schedule. No GL here;
// the hemicube provider runs one GL context (or one worker process) behind each thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>

#include "ffcube/formfactor/row_provider.hpp"
#include "ffcube/formfactor/sparse.hpp"

namespace ffcube {

class OrderedRowPool {
public:
    // Run on each worker's own thread: start before its first job (e.g. make a GL context
    // current there), stop after its last. Either may be empty.
    using Hook = std::function<void(unsigned worker)>;
    // Computes the row at position k of the current run() (row index i = rows[k]) into out, on
    // worker 'worker''s thread, with no lock held. Must be safe to call from several threads.
    using Compute = std::function<void(unsigned worker, std::size_t k, std::uint32_t i, SparseRow& out)>;

    // Starts 'workers' threads (≥ 1) and returns when each has run start; if one threw, stops
    // the others and rethrows the first exception.
    OrderedRowPool(unsigned workers, Hook start, Hook stop);
    ~OrderedRowPool();  // stops the workers (each runs stop) and joins them
    OrderedRowPool(const OrderedRowPool&) = delete;
    OrderedRowPool& operator=(const OrderedRowPool&) = delete;

    // Computes rows on the workers and calls sink(rows[k], row) for k = 0, 1, ... in order, on
    // the calling thread. At most 4 × workers rows are held (finished or in the works) at a
    // time. An exception from compute or sink ends the call and is rethrown; one from compute
    // stays: every later call rethrows it (the workers may hold broken state). Returns only when
    // no worker is still on a row of this call.
    void run(std::span<const std::uint32_t> rows, const Compute& compute, const RowSink& sink);

    // run() with each row in two halves, for workers that compute elsewhere (a child process):
    // submit(worker, k, i) starts row k and returns; collect(worker, k, i, out) waits for it and
    // finishes it. A worker submits its next row before it collects the last, so at most two of
    // its rows are in flight, collected in the order submitted; rows reach the sink in list order
    // as with run(). On an exception the worker drops both (the call rethrows it, and it stays).
    using Submit = std::function<void(unsigned worker, std::size_t k, std::uint32_t i)>;
    void run_pipelined(std::span<const std::uint32_t> rows, const Submit& submit, const Compute& collect,
                       const RowSink& sink);

    // Runs job on worker 0's thread (where its GL context is current) and waits for it; an
    // exception is rethrown, and stays as run's do.
    void run_on_first(const std::function<void()>& job);

    unsigned size() const;

private:
    void run_rows(std::span<const std::uint32_t> rows, const Submit* submit, const Compute& compute, const RowSink& sink);
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace ffcube
