#pragma once
/// Work items run in forked worker processes: each worker is forked once and then takes one
/// item after another, so what the parent built before (run plans, models) costs nothing per
/// item, and an item that crashes its worker costs only that item.

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace nimble::detection_power {

/// Runs `work(i)` for every i in [0, n) in min(jobs, n) forked workers, each item once, and
/// returns their results by index. `work` runs in a worker and returns one line (no newline).
/// A worker that dies while on item i gives died(i, how) for it ("killed by signal 11", "exit
/// code 3") and is replaced while items remain. `progress(done)` runs in the caller after each
/// item. The caller must have no other threads running (fork).
/// @throws std::runtime_error if a pipe or fork fails.
std::vector<std::string> run_in_workers(std::size_t n, int jobs, const std::function<std::string(std::size_t)>& work,
                                        const std::function<std::string(std::size_t, const std::string&)>& died,
                                        const std::function<void(std::size_t)>& progress = nullptr);

}  // namespace nimble::detection_power
