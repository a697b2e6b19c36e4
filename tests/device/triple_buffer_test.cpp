#include "torsion/device/triple_buffer.h"

#include <gtest/gtest.h>

#include <thread>

namespace torsion::device {
namespace {

struct Block {
  std::uint64_t a = 0, b = 0, c = 0, d = 0;
};

TEST(TripleBuffer, ReaderSeesNewestValueOnce) {
  TripleBuffer<Block> buffer;
  Block out;
  EXPECT_FALSE(buffer.read(out));
  buffer.write({1, 1, 1, 1});
  buffer.write({2, 2, 2, 2});
  EXPECT_TRUE(buffer.read(out));
  EXPECT_EQ(out.a, 2u);
  EXPECT_FALSE(buffer.read(out));  // nothing new: the same value again
  EXPECT_EQ(out.d, 2u);
}

TEST(TripleBuffer, ConcurrentReaderNeverSeesATornOrOlderValue) {
  TripleBuffer<Block> buffer;
  constexpr std::uint64_t kWrites = 200000;
  std::thread writer([&] {
    for (std::uint64_t k = 1; k <= kWrites; ++k)
      buffer.write({k, k, k, k});
  });
  std::uint64_t newest = 0;
  Block out;
  while (newest < kWrites) {
    buffer.read(out);
    ASSERT_EQ(out.a, out.b);
    ASSERT_EQ(out.a, out.c);
    ASSERT_EQ(out.a, out.d);
    ASSERT_GE(out.a, newest);
    newest = out.a;
  }
  writer.join();
}

}  // namespace
}  // namespace torsion::device
