// Built-in bitmap font and PNG files.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <set>

#include "mocap/viewer/bitmap_font.hpp"
#include "mocap/viewer/png_io.hpp"

namespace mocap::viewer {
namespace {

TEST(BitmapFont, EveryHudCharacterHasItsOwnGlyph) {
  const std::string chars = "ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789.,:;-+/()[]%=_!?'\"#<>*|";
  std::set<std::array<uint8_t, kGlyphH>> seen;
  for (char c : chars) {
    const auto& rows = glyph_rows(c);
    int ink = 0;
    for (uint8_t r : rows)
      ink += __builtin_popcount(r);
    EXPECT_GT(ink, 0) << c;
    EXPECT_TRUE(seen.insert(rows).second) << "glyph of '" << c << "' duplicates another";
  }
  EXPECT_EQ(glyph_index('a'), glyph_index('A'));
  EXPECT_EQ(glyph_index('\x01'), glyph_index('?'));
  EXPECT_EQ(glyph_index('~'), glyph_index('?'));
  int blank = 0;
  for (uint8_t r : glyph_rows(' '))
    blank += r;
  EXPECT_EQ(blank, 0);
}

TEST(BitmapFont, AtlasHoldsTheGlyphBits) {
  const FontAtlas a = make_font_atlas();
  ASSERT_EQ(a.width, kGlyphCount * kCellW);
  ASSERT_EQ(a.height, kCellH);
  const int g = glyph_index('T');
  // 'T': full top row, then only the middle column.
  for (int x = 0; x < kGlyphW; ++x)
    EXPECT_EQ(a.coverage[g * kCellW + x], 255);
  EXPECT_EQ(a.coverage[3 * a.width + g * kCellW + 2], 255);
  EXPECT_EQ(a.coverage[3 * a.width + g * kCellW + 0], 0);
  EXPECT_EQ(a.coverage[g * kCellW + kGlyphW], 0) << "spacing column stays empty";
}

TEST(PngIo, RoundTripKeepsEveryPixel) {
  RgbImage img;
  img.width = 37;
  img.height = 11;
  for (int i = 0; i < img.width * img.height * 3; ++i)
    img.rgb.push_back(static_cast<uint8_t>(i * 7 + 3));
  const std::string path = "/tmp/mocap-viewer-png-" + std::to_string(getpid()) + ".png";
  write_png(path, img);
  const RgbImage back = read_png(path);
  std::remove(path.c_str());
  EXPECT_EQ(back.width, 37);
  EXPECT_EQ(back.height, 11);
  EXPECT_EQ(back.rgb, img.rgb);
}

TEST(PngIo, BadFilesGiveErrorsNamingThem) {
  const std::string path = "/tmp/mocap-viewer-bad-" + std::to_string(getpid()) + ".png";
  FILE* f = std::fopen(path.c_str(), "wb");
  std::fputs("not a png at all", f);
  std::fclose(f);
  try {
    read_png(path);
    FAIL() << "garbage accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  }
  std::remove(path.c_str());
  EXPECT_THROW(read_png("/nonexistent/x.png"), std::runtime_error);
  EXPECT_THROW(write_png("/nonexistent/dir/x.png", RgbImage{1, 1, {0, 0, 0}}), std::runtime_error);
}

}  // namespace
}  // namespace mocap::viewer
