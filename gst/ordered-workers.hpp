// SPDX-License-Identifier: LGPL-2.1-or-later
// Frame threads of the pickdetect element: jobs run on a fixed set of threads and come back in
// the order they were submitted.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace gstpickdetect {

/// Runs jobs on `threads` threads of its own, oldest first, and hands them back strictly in the
/// order they were submitted, whichever finished first. Used from one thread (the streaming
/// thread) for submit / take; the jobs run on the workers.
class OrderedWorkers {
public:
  /// One unit of work; run() is called at most once, on a worker.
  class Job {
  public:
    virtual ~Job() = default;
    virtual void run() = 0;
  };

  /// Starts `threads` (at least 1) worker threads.
  explicit OrderedWorkers(int threads);
  /// Drops the jobs not started yet, waits for the running ones and stops the threads.
  ~OrderedWorkers();
  OrderedWorkers(const OrderedWorkers&) = delete;
  OrderedWorkers& operator=(const OrderedWorkers&) = delete;

  int threads() const { return static_cast<int>(workers_.size()); }

  /// Queues a job behind the others.
  void submit(std::unique_ptr<Job> job);

  /// Jobs submitted and not taken back yet (queued, running or done).
  std::size_t pending() const;

  /// The oldest job, once it has run: with `wait`, waits for it; without, returns null when it
  /// has not finished yet. Null when there is no job.
  std::unique_ptr<Job> take_oldest(bool wait);

  /// Takes every job back without running those that have not started (they are returned
  /// unrun, in order, after waiting for the running ones). For flushes and stops.
  std::vector<std::unique_ptr<Job>> cancel_all();

private:
  enum class State { Queued, Running, Done };
  struct Slot {
    std::unique_ptr<Job> job;
    State state = State::Queued;
  };

  void work();

  mutable std::mutex lock_;
  std::condition_variable queued_;          ///< Workers wait here for a queued job (or the end).
  std::condition_variable done_;            ///< The taker waits here for a job to finish.
  std::deque<std::shared_ptr<Slot>> slots_; ///< In submission order.
  bool quit_ = false;
  std::vector<std::thread> workers_;
};

} // namespace gstpickdetect
