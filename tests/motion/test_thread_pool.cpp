// Tests of hawor/parallel.hpp (native and WASM, where every pool runs on one thread): each task
// runs exactly once per run(), exceptions reach the caller and leave the pool usable, and many
// short fork–joins in a row (the infiller's pattern) neither lose nor repeat a task.
#include <catch2/catch.hpp>
#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

#include "hawor/parallel.hpp"

TEST_CASE("ThreadPool runs every task exactly once", "[parallel]") {
  for (int threads : {1, 2, 3, 8}) {
    hawor::ThreadPool pool(threads);
#ifdef HAWOR_NO_THREADS
    CHECK(pool.size() == 1);
#else
    CHECK(pool.size() == threads);
#endif
    for (int tasks : {0, 1, 2, 5, 64}) {
      std::vector<std::atomic<int>> count(static_cast<size_t>(tasks));
      for (auto& c : count) c = 0;
      pool.run(tasks, [&](int i) { count[static_cast<size_t>(i)].fetch_add(1); });
      for (int i = 0; i < tasks; ++i) CHECK(count[static_cast<size_t>(i)].load() == 1);
    }
  }
}

TEST_CASE("ThreadPool: thousands of short fork-joins in a row", "[parallel]") {
  hawor::ThreadPool pool(2);
  std::vector<long> sum(2, 0);  // each task writes its own slot: no data race by design
  long expect = 0;
  for (int round = 0; round < 3000; ++round) {
    pool.run(2, [&](int i) { sum[static_cast<size_t>(i)] += round + i; });
    expect += 2 * round + 1;
  }
  CHECK(sum[0] + sum[1] == expect);
}

TEST_CASE("ThreadPool: a task's exception reaches the caller; the pool stays usable",
          "[parallel]") {
  hawor::ThreadPool pool(3);
  std::atomic<int> ran{0};
  CHECK_THROWS_AS(pool.run(10,
                           [&](int i) {
                             ran.fetch_add(1);
                             if (i == 4) throw std::runtime_error("task 4");
                           }),
                  std::runtime_error);
  CHECK(ran.load() >= 1);
  CHECK(ran.load() <= 10);
  std::atomic<int> after{0};
  pool.run(7, [&](int) { after.fetch_add(1); });
  CHECK(after.load() == 7);
}

TEST_CASE("ThreadPool: tasks really run on more than one thread", "[parallel]") {
#ifdef HAWOR_NO_THREADS
  SUCCEED("no threads in this build: the pool is a plain loop");
#else
  hawor::ThreadPool pool(2);
  // Two tasks that each wait for the other: only completes when both run at the same time.
  std::atomic<int> arrived{0};
  pool.run(2, [&](int) {
    arrived.fetch_add(1);
    while (arrived.load() < 2) std::this_thread::yield();
  });
  CHECK(arrived.load() == 2);
#endif
}
