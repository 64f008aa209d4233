#include "ffcube/formfactor/ordered_pool.hpp"

#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

#include "ffcube/core/error.hpp"

namespace ffcube {

// run() hands out row positions through a counter ('next'); finished rows wait in a window of
// slots until the calling thread passes them to the sink in list order ('consumed'), so the
// output does not depend on which worker computed what, and memory stays bounded.
struct OrderedRowPool::Impl {
    Hook start_hook, stop_hook;
    std::vector<std::thread> threads;

    std::mutex mutex;
    std::condition_variable cv_work, cv_done;
    bool stopping = false;
    std::span<const std::uint32_t> rows;
    const Compute* compute = nullptr;  // run()'s, or run_pipelined()'s collect
    const Submit* submit = nullptr;    // run_pipelined()'s; null in run()
    std::size_t next = 0, consumed = 0, window = 0, in_flight = 0;
    std::vector<SparseRow> slots;
    std::vector<char> ready;
    std::exception_ptr error;  // the first worker failure; sticky
    unsigned started = 0;
    // run_on_first's job, served by worker 0.
    const std::function<void()>* job = nullptr;

    ~Impl() {
        {
            std::lock_guard lock(mutex);
            stopping = true;
        }
        cv_work.notify_all();
        for (auto& t : threads) t.join();
    }

    void fail(std::unique_lock<std::mutex>& lock) {
        if (!lock.owns_lock()) lock.lock();
        if (!error) error = std::current_exception();
    }

    void worker_main(unsigned index) {
        try {
            if (start_hook) start_hook(index);
        } catch (...) {
            std::unique_lock lock(mutex);
            fail(lock);
            ++started;
            cv_done.notify_all();
            return;
        }
        std::unique_lock lock(mutex);
        ++started;
        cv_done.notify_all();
        SparseRow row;
        // Pipelined runs: the row this worker submitted and has not collected (k, i), if any.
        constexpr std::size_t kNone = ~std::size_t{0};
        std::size_t held = kNone;
        std::uint32_t held_i = 0;
        const auto can_take = [&] { return next < rows.size() && next < consumed + window && !error; };
        for (;;) {
            cv_work.wait(lock, [&] { return stopping || (index == 0 && job) || held != kNone || can_take(); });
            if (stopping) break;
            if (held != kNone || (submit && can_take())) {
                // Submit the next row (when one may be taken), then collect the one held: the
                // worker computes the next while this thread finishes the last.
                std::size_t k = kNone;
                std::uint32_t i = 0;
                if (can_take()) {
                    k = next++;
                    i = rows[k];
                    ++in_flight;
                }
                const Submit* const s = submit;
                const Compute* const c = compute;
                const std::size_t mine = (k != kNone) + (held != kNone);
                lock.unlock();
                try {
                    if (k != kNone) (*s)(index, k, i);
                    if (held != kNone) (*c)(index, held, held_i, row);
                } catch (...) {
                    fail(lock);
                    in_flight -= mine;  // both dropped: the error stays, nothing more is delivered
                    held = kNone;
                    cv_done.notify_all();
                    continue;
                }
                lock.lock();
                if (held != kNone) {
                    std::swap(slots[held % window], row);
                    ready[held % window] = 1;
                    --in_flight;
                    cv_done.notify_all();
                }
                held = k;
                held_i = i;
                continue;
            }
            if (index == 0 && job) {
                const std::function<void()>* const j = job;
                lock.unlock();
                try {
                    (*j)();
                } catch (...) {
                    fail(lock);
                }
                if (!lock.owns_lock()) lock.lock();
                job = nullptr;
                cv_done.notify_all();
                continue;
            }
            const std::size_t k = next++;
            const std::uint32_t i = rows[k];
            const Compute* const c = compute;
            ++in_flight;
            lock.unlock();
            try {
                (*c)(index, k, i, row);
            } catch (...) {
                fail(lock);
                --in_flight;
                cv_done.notify_all();
                continue;
            }
            lock.lock();
            std::swap(slots[k % window], row);
            ready[k % window] = 1;
            --in_flight;
            cv_done.notify_all();
        }
        lock.unlock();
        if (stop_hook) stop_hook(index);
    }
};

OrderedRowPool::OrderedRowPool(unsigned workers, Hook start, Hook stop) : impl_(std::make_unique<Impl>()) {
    FFCUBE_CHECK_MSG(workers >= 1, "a row pool needs a worker");
    Impl& im = *impl_;
    im.start_hook = std::move(start);
    im.stop_hook = std::move(stop);
    for (unsigned t = 0; t < workers; ++t) im.threads.emplace_back([&im, t] { im.worker_main(t); });
    std::unique_lock lock(im.mutex);
    im.cv_done.wait(lock, [&] { return im.started == workers; });
    if (im.error) {
        std::exception_ptr e = im.error;
        lock.unlock();
        impl_.reset();  // joins the threads that did start
        std::rethrow_exception(e);
    }
}

OrderedRowPool::~OrderedRowPool() = default;

unsigned OrderedRowPool::size() const { return static_cast<unsigned>(impl_->threads.size()); }

void OrderedRowPool::run(std::span<const std::uint32_t> rows, const Compute& compute, const RowSink& sink) {
    run_rows(rows, nullptr, compute, sink);
}

void OrderedRowPool::run_pipelined(std::span<const std::uint32_t> rows, const Submit& submit, const Compute& collect,
                                   const RowSink& sink) {
    run_rows(rows, &submit, collect, sink);
}

void OrderedRowPool::run_rows(std::span<const std::uint32_t> rows, const Submit* submit, const Compute& compute,
                              const RowSink& sink) {
    Impl& im = *impl_;
    if (rows.empty()) return;
    std::unique_lock lock(im.mutex);
    if (im.error) std::rethrow_exception(im.error);
    im.rows = rows;
    im.compute = &compute;
    im.submit = submit;
    im.next = 0;
    im.consumed = 0;
    im.window = 4 * im.threads.size();
    im.slots.resize(im.window);
    im.ready.assign(im.window, 0);
    im.cv_work.notify_all();
    // However this call ends (done, a worker failed, the sink threw), no worker may still be
    // reading 'rows' or writing a slot when it returns.
    auto finish = [&] {
        im.next = im.rows.size();
        im.cv_done.wait(lock, [&] { return im.in_flight == 0; });
        im.rows = {};
        im.compute = nullptr;
        im.submit = nullptr;
    };
    SparseRow current;
    try {
        for (std::size_t k = 0; k < rows.size(); ++k) {
            im.cv_done.wait(lock, [&] { return im.ready[k % im.window] || im.error; });
            if (im.error) std::rethrow_exception(im.error);
            std::swap(current, im.slots[k % im.window]);
            im.ready[k % im.window] = 0;
            ++im.consumed;
            im.cv_work.notify_all();
            lock.unlock();
            sink(rows[k], current);
            lock.lock();
        }
    } catch (...) {
        if (!lock.owns_lock()) lock.lock();
        finish();
        throw;
    }
    finish();
}

void OrderedRowPool::run_on_first(const std::function<void()>& job) {
    Impl& im = *impl_;
    std::unique_lock lock(im.mutex);
    if (im.error) std::rethrow_exception(im.error);
    im.job = &job;
    im.cv_work.notify_all();
    im.cv_done.wait(lock, [&] { return im.job == nullptr; });
    if (im.error) std::rethrow_exception(im.error);
}

}  // namespace ffcube
