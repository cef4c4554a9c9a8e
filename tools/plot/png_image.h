#pragma once
// A small RGB raster and its PNG encoding (ISO/IEC 15948 / W3C PNG 2nd ed.): 8-bit truecolour, no interlace,
// filter 0 on every row, one zlib stream in one IDAT chunk. Used by `fmpc plot`; only tools/ draw pictures.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace fmpc::plot {

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb& other) const { return r == other.r && g == other.g && b == other.b; }
};

class RgbImage {
 public:
  RgbImage(int width, int height, Rgb background);
  int width() const { return width_; }
  int height() const { return height_; }
  // Pixels outside the image are ignored, so drawing code need not clip.
  void set(int x, int y, Rgb colour);
  Rgb at(int x, int y) const;  // precondition: inside
  void fill_rect(int x, int y, int w, int h, Rgb colour);
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }  // row-major, 3 bytes per pixel

 private:
  int width_;
  int height_;
  std::vector<std::uint8_t> bytes_;
};

// CRC-32 of PNG chunks (ISO 3309 / ITU-T V.42 polynomial 0xEDB88320, reflected), continuing from `crc` (0 to
// start).
std::uint32_t png_crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0);

// The complete PNG file. The image data is deflated with zlib (Debian zlib1g): a stored (uncompressed) stream
// would make a 640x530 figure 1 MB instead of tens of kB.
std::string encode_png(const RgbImage& image);

}  // namespace fmpc::plot
