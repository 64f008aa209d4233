#include "ffcube/solver/convergence.hpp"

#include "ffcube/core/error.hpp"

namespace ffcube {

std::string to_string(StopReason r) {
    switch (r) {
        case StopReason::Running: return "running";
        case StopReason::Converged: return "converged";
        case StopReason::IterationLimit: return "iteration_limit";
        case StopReason::Diverged: return "diverged";
        case StopReason::NothingToDo: return "nothing_to_do";
    }
    FFCUBE_CHECK_MSG(false, "unknown StopReason");
}

bool DivergenceMonitor::update(double value) {
    if (!std::isfinite(value)) return true;
    if (value < best_) {
        best_ = value;
        since_best_ = 0;
        return false;
    }
    ++since_best_;
    return since_best_ >= window_ && value > growth_ * best_;
}

ConvergenceHistory::ConvergenceHistory(std::size_t capacity) : capacity_(capacity) {
    FFCUBE_CHECK(capacity >= 2);
    samples_.reserve(capacity);
}

void ConvergenceHistory::offer(double seconds, double unshot_fraction) {
    if (offered_++ % stride_ != 0) return;
    if (samples_.size() == capacity_) {
        // Keep samples 0, 2, 4, ...: they are the multiples of the doubled stride.
        std::size_t kept = 0;
        for (std::size_t k = 0; k < samples_.size(); k += 2) samples_[kept++] = samples_[k];
        samples_.resize(kept);
        stride_ *= 2;
        if ((offered_ - 1) % stride_ != 0) return;
    }
    samples_.push_back({seconds, unshot_fraction});
}

void ConvergenceHistory::finish(double seconds, double unshot_fraction) {
    if (!samples_.empty() && samples_.back().seconds == seconds && samples_.back().unshot_fraction == unshot_fraction)
        return;
    if (samples_.size() == capacity_) samples_.pop_back();
    samples_.push_back({seconds, unshot_fraction});
}

void ConvergenceHistory::clear() {
    stride_ = 1;
    offered_ = 0;
    samples_.clear();
}

}  // namespace ffcube
