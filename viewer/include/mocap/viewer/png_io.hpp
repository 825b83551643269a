// PNG files for screenshots (write) and for the tests that inspect them (read), via libpng.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace mocap::viewer {

/// 8-bit RGB image, rows top to bottom.
struct RgbImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;
  const uint8_t* at(int x, int y) const {
    return &rgb[(static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) * 3];
  }
};

/// Writes the image; throws std::runtime_error naming the file on failure.
void write_png(const std::string& path, const RgbImage& image);
/// Reads an 8-bit RGB or RGBA PNG (alpha dropped); throws std::runtime_error on failure.
RgbImage read_png(const std::string& path);

}  // namespace mocap::viewer
