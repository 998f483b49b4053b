// RunTasks, which the normals command encodes its images with: every task runs once, several at
// a time, and a failure is reported as the first failing task's, in the order given, whatever
// the thread that ran it.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/parallel.h"

namespace iphong {
namespace {

TEST(RunTasks, RunsEveryTaskOnce) {
  for (int threads : {1, 2, 5}) {
    std::vector<std::atomic<int>> runs(17);
    std::vector<std::function<void()>> tasks;
    for (std::size_t i = 0; i < runs.size(); ++i) tasks.push_back([&runs, i] { ++runs[i]; });
    RunTasks(tasks, threads);
    for (const auto& r : runs) EXPECT_EQ(r.load(), 1) << threads << " threads";
  }
}

TEST(RunTasks, RunsTasksSideBySide) {
  // Two tasks that each wait for the other to start finish only if they run at once.
  std::atomic<int> started{0};
  const auto meet = [&] {
    ++started;
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (started.load() < 2 && std::chrono::steady_clock::now() < until) {
      std::this_thread::yield();
    }
    if (started.load() < 2) throw std::runtime_error("ran alone");
  };
  RunTasks({meet, meet}, 2);
}

TEST(RunTasks, ReportsTheFirstFailureInTaskOrderAfterRunningTheRest) {
  for (int threads : {1, 2, 4}) {
    std::atomic<int> ran{0};
    std::vector<std::function<void()>> tasks;
    for (int i = 0; i < 6; ++i) {
      tasks.push_back([&ran, i] {
        // The later failure finishes first: task 4 at once, task 2 after a pause.
        if (i == 2) std::this_thread::sleep_for(std::chrono::milliseconds(50));
        ++ran;
        if (i == 2 || i == 4) throw std::runtime_error("task " + std::to_string(i));
      });
    }
    try {
      RunTasks(tasks, threads);
      ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "task 2") << threads << " threads";
    }
    EXPECT_EQ(ran.load(), 6);
  }
}

}  // namespace
}  // namespace iphong
