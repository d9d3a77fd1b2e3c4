#pragma once
/// @file spsc_queue.hpp
/// Bounded single-producer / single-consumer ring buffer: the hand-off between a device's
/// reader thread (which must never stall its socket) and the consumer (monitor, recorder).
///
/// Lock-free: the producer owns `head_`, the consumer owns `tail_`; each reads the other's
/// index with acquire and publishes its own with release (the classic Lamport queue, as in
/// folly::ProducerConsumerQueue / boost::lockfree::spsc_queue). A full queue makes try_push()
/// return false — the producer decides what to drop; it never waits. The consumer may block in
/// wait_pop(): it sleeps on a condition variable that the producer signals only when the
/// consumer has announced it is sleeping (a flag plus a fence on each side), so the fast path
/// stays lock-free and an idle consumer costs no CPU.
#include <atomic>
#include <chrono>
#include <cstddef>
#include <condition_variable>
#include <mutex>
#include <vector>

namespace twinwatch {

template <class T>
class SpscQueue {
 public:
  /// @param capacity number of elements the queue can hold (≥ 1).
  explicit SpscQueue(std::size_t capacity) : slots_(capacity + 1) {}
  SpscQueue(const SpscQueue&) = delete;
  SpscQueue& operator=(const SpscQueue&) = delete;

  std::size_t capacity() const { return slots_.size() - 1; }

  /// Producer only. Returns false (and leaves the queue unchanged) when full.
  bool try_push(const T& value) {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    const std::size_t next = head + 1 == slots_.size() ? 0 : head + 1;
    if (next == tail_.load(std::memory_order_acquire)) return false;
    slots_[head] = value;
    head_.store(next, std::memory_order_release);
    std::atomic_thread_fence(std::memory_order_seq_cst);  // pairs with the fence in wait_pop
    if (sleeping_.load(std::memory_order_relaxed)) {
      std::lock_guard<std::mutex> lock(mutex_);
      cv_.notify_one();
    }
    return true;
  }

  /// Consumer only. Returns false when empty.
  bool try_pop(T& out) {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    out = slots_[tail];
    tail_.store(tail + 1 == slots_.size() ? 0 : tail + 1, std::memory_order_release);
    return true;
  }

  /// Consumer only. Waits up to `timeout` for an element. Returns false on timeout.
  bool wait_pop(T& out, std::chrono::nanoseconds timeout) {
    if (try_pop(out)) return true;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    std::unique_lock<std::mutex> lock(mutex_);
    sleeping_.store(true, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_seq_cst);  // announce before re-checking head
    const bool got = cv_.wait_until(lock, deadline, [&] {
      return tail_.load(std::memory_order_relaxed) != head_.load(std::memory_order_acquire);
    });
    sleeping_.store(false, std::memory_order_relaxed);
    lock.unlock();
    return got && try_pop(out);
  }

  /// Approximate number of queued elements (exact when called by either side while the other
  /// is idle).
  std::size_t size() const {
    const std::size_t h = head_.load(std::memory_order_acquire), t = tail_.load(std::memory_order_acquire);
    return h >= t ? h - t : h + slots_.size() - t;
  }

 private:
  std::vector<T> slots_;
  alignas(64) std::atomic<std::size_t> head_{0};  // next slot to write (producer)
  alignas(64) std::atomic<std::size_t> tail_{0};  // next slot to read (consumer)
  alignas(64) std::atomic<bool> sleeping_{false};  // consumer is (about to be) in cv_.wait
  std::mutex mutex_;
  std::condition_variable cv_;
};

}  // namespace twinwatch
