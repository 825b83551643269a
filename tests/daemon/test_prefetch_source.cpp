// PrefetchSource: the read-ahead thread hands samples over in order, across chunk boundaries,
// passes the reader's error and calibration on, and can be dropped mid-stream.
#include <gtest/gtest.h>

#include "mocap/daemon/prefetch_source.hpp"

namespace mocap::daemon {
namespace {

/// n samples with seq 0..n-1, then the end (with an error message if given).
class CountingSource final : public SampleSource {
 public:
  CountingSource(uint32_t n, std::string error_at_end)
      : n_(n), end_error_(std::move(error_at_end)) {}
  const Config& config() const override { return cfg_; }
  bool next(ImuSample& out) override {
    if (i_ == n_) {
      error_ = end_error_;
      return false;
    }
    out = ImuSample{};
    out.seq = i_;
    out.t_host_ns = int64_t{i_} * 1000;
    ++i_;
    return true;
  }
  const std::string& error() const override { return error_; }
  double progress() const override { return static_cast<double>(i_) / n_; }
  std::string calibration_text() const override { return "calibration"; }

 private:
  Config cfg_;
  uint32_t n_, i_ = 0;
  std::string end_error_, error_;
};

TEST(PrefetchSource, DeliversEverySampleInOrderAcrossChunks) {
  const uint32_t n = 3 * PrefetchSource::kChunk + 17;
  PrefetchSource src(std::make_unique<CountingSource>(n, ""));
  EXPECT_EQ(src.calibration_text(), "calibration");
  ImuSample s;
  uint32_t count = 0;
  while (src.next(s)) {
    ASSERT_EQ(s.seq, count);
    ++count;
  }
  EXPECT_EQ(count, n);
  EXPECT_TRUE(src.error().empty());
  EXPECT_DOUBLE_EQ(src.progress(), 1.0);
  EXPECT_FALSE(src.next(s));  // stays at the end
}

TEST(PrefetchSource, PassesTheReadersErrorOnAfterTheLastGoodSample) {
  PrefetchSource src(std::make_unique<CountingSource>(PrefetchSource::kChunk, "torn block at 99"));
  ImuSample s;
  uint32_t count = 0;
  while (src.next(s))
    ++count;
  EXPECT_EQ(count, PrefetchSource::kChunk);
  EXPECT_EQ(src.error(), "torn block at 99");
}

TEST(PrefetchSource, CanBeDroppedMidStreamAndWhenEmpty) {
  for (int k = 0; k < 20; ++k) {
    PrefetchSource src(std::make_unique<CountingSource>(10 * PrefetchSource::kChunk, ""));
    ImuSample s;
    for (int i = 0; i < k * 500; ++i)
      ASSERT_TRUE(src.next(s));
  }  // destructors stop the reader whether it is blocked on a full queue or still reading
  PrefetchSource empty(std::make_unique<CountingSource>(0, ""));
  ImuSample s;
  EXPECT_FALSE(empty.next(s));
}

}  // namespace
}  // namespace mocap::daemon
