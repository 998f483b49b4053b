// Memory sizes as people write them (core/resources.h).
#include <gtest/gtest.h>

#include "core/resources.h"

namespace iphong {
namespace {

std::uint64_t Bytes(const std::string& text) {
  std::uint64_t bytes = 0;
  const std::string m = ParseMemorySize(text, &bytes);
  EXPECT_EQ(m, "") << text;
  return bytes;
}

std::string Refusal(const std::string& text) {
  std::uint64_t bytes = 7;
  const std::string m = ParseMemorySize(text, &bytes);
  EXPECT_EQ(bytes, 7u) << text << ": a refused size leaves the value alone";
  return m;
}

TEST(MemorySize, PlainNumbersAreGbAndUnitsAreThoseDaskReads) {
  EXPECT_EQ(Bytes("16"), 16000000000u);
  EXPECT_EQ(Bytes("0.5"), 500000000u);
  EXPECT_EQ(Bytes("16GB"), 16000000000u);
  EXPECT_EQ(Bytes("16 gb"), 16000000000u);
  EXPECT_EQ(Bytes("16G"), 16000000000u);
  EXPECT_EQ(Bytes("512M"), 512000000u);
  EXPECT_EQ(Bytes("512MB"), 512000000u);
  EXPECT_EQ(Bytes("800k"), 800000u);
  EXPECT_EQ(Bytes("2T"), 2000000000000u);
  EXPECT_EQ(Bytes("1.5GiB"), 1610612736u);
  EXPECT_EQ(Bytes("1MiB"), 1048576u);
  EXPECT_EQ(Bytes("2e9B"), 2000000000u);
  EXPECT_EQ(Bytes("1B"), 1u);
  EXPECT_EQ(Bytes("1e9"), 1000000000000000000u);  // the largest: 1e9 GB
}

TEST(MemorySize, WhatCannotBeALimitIsRefusedNotTruncated) {
  // Below a byte used to truncate to 0, the "unset" value; past 2^64 bytes the conversion was
  // undefined behaviour that also landed on the default.
  EXPECT_EQ(Refusal("1e-12"), "'1e-12' is less than one byte");
  EXPECT_EQ(Refusal("1e308"), "'1e308' is more than 1e9 GB");
  EXPECT_EQ(Refusal("inf"), "'inf' is more than 1e9 GB");
  EXPECT_EQ(Refusal("0"), "'0' must be a size > 0");
  EXPECT_EQ(Refusal("-4GB"), "'-4GB' must be a size > 0");
  EXPECT_EQ(Refusal("nan"), "'nan' must be a size > 0");
  EXPECT_NE(Refusal("16XB").find("unknown unit 'xb'"), std::string::npos);
  EXPECT_NE(Refusal("lots").find("is not a size"), std::string::npos);
  EXPECT_NE(Refusal("").find("is not a size"), std::string::npos);
  std::uint64_t bytes = 0;
  EXPECT_EQ(MemorySizeFromGb(1e-12, &bytes), "is less than one byte");
  EXPECT_EQ(MemorySizeFromGb(2, &bytes), "");
  EXPECT_EQ(bytes, 2000000000u);
}

TEST(MemorySize, RefusalsQuoteTheLimitInItsOwnUnit) {
  EXPECT_EQ(FormatBytes(1), "1 B");
  EXPECT_EQ(FormatBytes(512e6), "512 MB");
  MemoryLimit limit;
  limit.bytes = 512000000;
  EXPECT_EQ(limit.Check(1e9, "the capture"),
            "the capture needs 1.0 GB, more than the memory limit of 512 MB (raise it with "
            "--memory-limit)");
  EXPECT_EQ(limit.Check(1e6, "the capture"), "");
}

}  // namespace
}  // namespace iphong
