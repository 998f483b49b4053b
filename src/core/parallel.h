// A minimal parallel loop: [begin, end) cut into chunks handed out to worker threads.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <functional>
#include <system_error>
#include <thread>
#include <vector>

namespace iphong {

// Requests beyond this are clamped: more threads than this only cost memory and start-up.
constexpr int kMaxThreads = 1024;

inline int ResolveThreads(int threads) {
  if (threads > 0) return std::min(threads, kMaxThreads);
  const unsigned hardware = std::thread::hardware_concurrency();
  return hardware == 0 ? 1 : static_cast<int>(hardware);
}

// Calls body(chunk_begin, chunk_end) for consecutive chunks of at most `chunk` items, from up to
// `threads` threads (0 = hardware concurrency). The body must not throw.
template <typename Body>
void ParallelFor(std::size_t begin, std::size_t end, std::size_t chunk, int threads, Body body) {
  if (end <= begin) return;
  chunk = std::max<std::size_t>(chunk, 1);
  const std::size_t chunks = (end - begin + chunk - 1) / chunk;
  const int workers = static_cast<int>(std::min<std::size_t>(ResolveThreads(threads), chunks));
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t c = next++; c < chunks; c = next++) {
      const std::size_t b = begin + c * chunk;
      body(b, std::min(end, b + chunk));
    }
  };
  if (workers <= 1) {
    work();
    return;
  }
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  for (int w = 1; w < workers; ++w) {
    // Under a process or memory limit a thread may not start: the chunks are shared, so the
    // threads that did start (at least this one) do all the work.
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {
      break;
    }
  }
  work();
  for (auto& t : pool) t.join();
}

// Runs every task, up to `threads` at once (0 = hardware concurrency), each taken in the order
// given by the next free thread. Every task runs even when another throws; then the exception of
// the first task in that order that threw is rethrown.
inline void RunTasks(const std::vector<std::function<void()>>& tasks, int threads) {
  std::vector<std::exception_ptr> errors(tasks.size());
  ParallelFor(0, tasks.size(), 1, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      try {
        tasks[i]();
      } catch (...) {
        errors[i] = std::current_exception();
      }
    }
  });
  for (const std::exception_ptr& error : errors) {
    if (error) std::rethrow_exception(error);
  }
}

}  // namespace iphong
