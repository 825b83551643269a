// A tiny built-in 5x7 bitmap font (upper-case ASCII, digits, punctuation) so the heads-up
// display needs no font files. Lower case is drawn as upper case; unknown characters as '?'.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace mocap::viewer {

inline constexpr int kGlyphW = 5, kGlyphH = 7;
/// Each glyph sits in a cell with one pixel of spacing right and two below.
inline constexpr int kCellW = 6, kCellH = 9;
/// Cells in the atlas: characters 32..126 plus a solid block (index 95) for panels.
inline constexpr int kGlyphCount = 96;
inline constexpr char kSolidBlock = 127;

/// Atlas cell of a character (0..95).
int glyph_index(char c);
/// Rows top to bottom, bit 4 = leftmost pixel.
const std::array<uint8_t, kGlyphH>& glyph_rows(char c);

/// Coverage atlas (255 ink, 0 empty): kGlyphCount cells side by side, kCellW x kCellH each,
/// rows top to bottom.
struct FontAtlas {
  int width = 0, height = 0;
  std::vector<uint8_t> coverage;
};
FontAtlas make_font_atlas();

}  // namespace mocap::viewer
