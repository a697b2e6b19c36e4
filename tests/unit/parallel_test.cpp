// TORSION_THREADS: the default thread count (a request of 0) for runs side by side.

#include "torsion/solve/parallel.h"

#include <gtest/gtest.h>
#include <tbb/info.h>

#include <cstdlib>
#include <optional>
#include <string>

namespace torsion {
namespace {

// Sets TORSION_THREADS for one test and puts back what was there.
class ThreadsVariable {
 public:
  explicit ThreadsVariable(const char* value) {
    if (const char* old = std::getenv(kThreadsVariable)) previous_ = old;
    if (value != nullptr) {
      setenv(kThreadsVariable, value, 1);
    } else {
      unsetenv(kThreadsVariable);
    }
  }
  ~ThreadsVariable() {
    if (previous_) {
      setenv(kThreadsVariable, previous_->c_str(), 1);
    } else {
      unsetenv(kThreadsVariable);
    }
  }
  ThreadsVariable(const ThreadsVariable&) = delete;
  ThreadsVariable& operator=(const ThreadsVariable&) = delete;

 private:
  std::optional<std::string> previous_;
};

TEST(ThreadsVariable, UnsetMeansEveryCore) {
  const ThreadsVariable unset(nullptr);
  EXPECT_EQ(Parallel(0).threads(), tbb::info::default_concurrency());
  EXPECT_FALSE(threadsFromEnvironment().has_value());
}

TEST(ThreadsVariable, SetsTheDefaultButNotAnExplicitRequest) {
  const ThreadsVariable one("1");
  EXPECT_EQ(threadsFromEnvironment(), 1);
  EXPECT_EQ(Parallel(0).threads(), 1);
  EXPECT_EQ(Parallel::usableThreads(-1), 1);
  // A request for a count is the caller's: TORSION_THREADS does not override it.
  EXPECT_EQ(Parallel(2).threads(), std::min(2, tbb::info::default_concurrency()));
}

TEST(ThreadsVariable, MoreThanTheMachineHasIsCappedAtItsCores) {
  const ThreadsVariable many("4096");
  EXPECT_EQ(threadsFromEnvironment(), 4096);
  EXPECT_EQ(Parallel(0).threads(), tbb::info::default_concurrency());
}

TEST(ThreadsVariable, AMalformedValueIsIgnored) {
  for (const char* bad : {"", "0", "-1", "two", "3x", " 2", "4097", "99999999999999999999"}) {
    const ThreadsVariable value(bad);
    EXPECT_FALSE(threadsFromEnvironment().has_value()) << "'" << bad << "'";
    EXPECT_EQ(Parallel(0).threads(), tbb::info::default_concurrency()) << "'" << bad << "'";
  }
}

}  // namespace
}  // namespace torsion
