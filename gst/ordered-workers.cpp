// SPDX-License-Identifier: LGPL-2.1-or-later
#include "ordered-workers.hpp"

#include <algorithm>

namespace gstpickdetect {

OrderedWorkers::OrderedWorkers(int threads) {
  const int n = std::max(1, threads);
  workers_.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i)
    workers_.emplace_back([this] { work(); });
}

OrderedWorkers::~OrderedWorkers() {
  cancel_all();
  {
    std::lock_guard<std::mutex> hold(lock_);
    quit_ = true;
  }
  queued_.notify_all();
  for (std::thread& t : workers_)
    t.join();
}

void OrderedWorkers::submit(std::unique_ptr<Job> job) {
  auto slot = std::make_shared<Slot>();
  slot->job = std::move(job);
  {
    std::lock_guard<std::mutex> hold(lock_);
    slots_.push_back(std::move(slot));
  }
  queued_.notify_one();
}

std::size_t OrderedWorkers::pending() const {
  std::lock_guard<std::mutex> hold(lock_);
  return slots_.size();
}

std::unique_ptr<OrderedWorkers::Job> OrderedWorkers::take_oldest(bool wait) {
  std::unique_lock<std::mutex> hold(lock_);
  if (slots_.empty())
    return nullptr;
  const std::shared_ptr<Slot> oldest = slots_.front();
  if (wait)
    done_.wait(hold, [&] { return oldest->state == State::Done; });
  else if (oldest->state != State::Done)
    return nullptr;
  slots_.pop_front();
  return std::move(oldest->job);
}

std::vector<std::unique_ptr<OrderedWorkers::Job>> OrderedWorkers::cancel_all() {
  std::unique_lock<std::mutex> hold(lock_);
  std::deque<std::shared_ptr<Slot>> slots;
  slots.swap(slots_);
  // Queued slots are no longer in slots_, so no worker will start them.
  done_.wait(hold, [&] {
    return std::none_of(slots.begin(), slots.end(),
                        [](const std::shared_ptr<Slot>& s) { return s->state == State::Running; });
  });
  std::vector<std::unique_ptr<Job>> jobs;
  for (const std::shared_ptr<Slot>& s : slots)
    jobs.push_back(std::move(s->job));
  return jobs;
}

void OrderedWorkers::work() {
  std::unique_lock<std::mutex> hold(lock_);
  for (;;) {
    std::shared_ptr<Slot> slot;
    queued_.wait(hold, [&] {
      if (quit_)
        return true;
      for (const std::shared_ptr<Slot>& s : slots_) {
        if (s->state == State::Queued) {
          slot = s;
          return true;
        }
      }
      return false;
    });
    if (!slot)
      return; // quit_
    slot->state = State::Running;
    hold.unlock();
    slot->job->run();
    hold.lock();
    slot->state = State::Done;
    done_.notify_all();
  }
}

} // namespace gstpickdetect
