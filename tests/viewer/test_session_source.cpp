// Session playback in the viewer: a real session file written by SessionWriter, indexed and
// played by SessionSource (timing, pause, seek, loop, body proportions, torn tail, bad files).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "mocap/session/session_writer.hpp"
#include "mocap/viewer/pose_source.hpp"
#include "mocap/viewer/session_source.hpp"

namespace mocap::viewer {
namespace {

namespace fs = std::filesystem;

struct TempDir {
  fs::path path = fs::temp_directory_path() / ("mocap_viewer_session_" + std::to_string(getpid()));
  TempDir() { fs::create_directories(path); }
  ~TempDir() { fs::remove_all(path); }
};

// `n` frames at 100 Hz of a 1.62 m body standing still, frame numbers 1000 + k.
std::string write_session(const fs::path& dir, int n) {
  const BodyDimensions dims = body_dimensions_from_height(1.62);
  session::SessionHeader header;
  header.config_text = "[body]\nheight_m = 1.62\n";
  std::string error;
  const std::string path = (dir / "take.mocap").string();
  auto w = SessionWriter::create(path, header, {}, &error);
  EXPECT_TRUE(w) << error;
  for (int k = 0; k < n; ++k) {
    PoseFrame f = reference_pose(dims, {0.01f * static_cast<float>(k), 0, 0});
    f.frame = 1000 + static_cast<uint64_t>(k);
    f.t_ns = 7'000'000'000 + int64_t{k} * 10'000'000;
    f.flags = kFrameRecording | kFrameCalibrated;
    EXPECT_TRUE(w->append_pose(f));
  }
  EXPECT_TRUE(w->close()) << w->stats().error;
  return path;
}

TEST(SessionSource, PlaysRecordedFramesAtTheirTimingWithTheRecordedProportions) {
  TempDir tmp;
  SessionSource src(write_session(tmp.path, 200));
  EXPECT_EQ(src.frame_count(), 200);
  EXPECT_NEAR(src.duration_s(), 1.99, 1e-9);
  ASSERT_NE(src.dimensions(), nullptr);
  EXPECT_NEAR(src.dimensions()->height_m, 1.62, 1e-3);

  std::vector<PoseFrame> frames;
  ASSERT_TRUE(src.poll(0.0, frames));
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].frame, 1000u);
  EXPECT_TRUE(frames[0].flags & kFrameReplay);
  EXPECT_FALSE(frames[0].flags & kFrameRecording);  // playing back is not recording
  EXPECT_FALSE(src.poll(0.004, frames));            // same frame: nothing changed
  ASSERT_TRUE(src.poll(0.505, frames));
  EXPECT_EQ(frames[0].frame, 1050u);
  EXPECT_NEAR(frames[0].p_earth_segment_m[0][0], 0.50f, 1e-5f);
  EXPECT_NE(src.status().find("FRAME 51/200"), std::string::npos) << src.status();
}

TEST(SessionSource, PausesSeeksAndLoops) {
  TempDir tmp;
  SessionSource src(write_session(tmp.path, 100));  // 1.0 s loop (0.99 s + one frame)
  std::vector<PoseFrame> frames;
  src.poll(0.2, frames);
  EXPECT_EQ(frames[0].frame, 1020u);
  src.set_paused(true);
  src.poll(5.0, frames);
  EXPECT_EQ(frames[0].frame, 1020u);
  src.seek_by(0.3);
  src.poll(5.1, frames);
  EXPECT_EQ(frames[0].frame, 1050u);
  src.seek_by(-0.6);  // before the start: wraps to the end
  src.poll(5.2, frames);
  EXPECT_EQ(frames[0].frame, 1090u);
  src.set_paused(false);
  src.poll(5.35, frames);  // 0.9 + 0.15 = 1.05 s: looped to 0.05 s
  EXPECT_EQ(frames[0].frame, 1005u);
  EXPECT_EQ(src.frame_at(-0.005), 99);
}

TEST(SessionSource, TornTailPlaysEverythingBeforeItAndSaysSo) {
  TempDir tmp;
  const std::string path = write_session(tmp.path, 50);
  fs::resize_file(path, fs::file_size(path) - 100);  // cut into the last block
  SessionSource src(path);
  EXPECT_EQ(src.frame_count(), 49);
  std::vector<PoseFrame> frames;
  src.poll(0.485, frames);
  EXPECT_EQ(frames[0].frame, 1048u);
  EXPECT_NE(src.status().find("ENDS EARLY"), std::string::npos) << src.status();
}

TEST(SessionSource, RefusesFilesItCannotPlayWithTheReason) {
  TempDir tmp;
  const fs::path bogus = tmp.path / "notes.txt";
  std::ofstream(bogus) << "HIERARCHY? no, just text\n";
  try {
    SessionSource src(bogus.string());
    FAIL() << "opened a text file";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not a mocap session file"), std::string::npos)
        << e.what();
  }
  // A valid session without pose frames (a recording stopped before the first frame).
  std::string error;
  const std::string empty = (tmp.path / "empty.mocap").string();
  auto w = SessionWriter::create(empty, {}, {}, &error);
  ASSERT_TRUE(w) << error;
  w->close();
  try {
    SessionSource src(empty);
    FAIL() << "played a session without poses";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no pose frames"), std::string::npos) << e.what();
  }
}

TEST(SessionSource, BodyHeightComesBackFromRecordedJointPositions) {
  for (double h : {1.5, 1.75, 1.98}) {
    const PoseFrame f = reference_pose(body_dimensions_from_height(h), {0, 0, 0});
    EXPECT_NEAR(body_height_from_pose(f, 1.0), h, 1e-4);
  }
  PoseFrame zero;
  reset_pose(zero);  // every joint at the origin
  EXPECT_EQ(body_height_from_pose(zero, 1.7), 1.7);
}

}  // namespace
}  // namespace mocap::viewer
