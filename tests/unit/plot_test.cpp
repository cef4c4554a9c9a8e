// PNG writer, bitmap font and heat maps (tools/plot/): the file is checked byte by byte against the PNG
// specification with an independent CRC and zlib's own inflate.
#include <catch2/catch.hpp>
#include <zlib.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "tools/plot/bitmap_font.h"
#include "tools/plot/heat_map.h"
#include "tools/plot/png_image.h"

using namespace fmpc::plot;

namespace {

std::uint32_t read_u32(const std::string& s, std::size_t at) {
  return (static_cast<std::uint32_t>(static_cast<unsigned char>(s.at(at))) << 24) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(s.at(at + 1))) << 16) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(s.at(at + 2))) << 8) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(s.at(at + 3)));
}

// Bit-at-a-time CRC-32 (reflected 0xEDB88320), written independently of the table-driven one under test.
std::uint32_t slow_crc32(const std::string& bytes) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (char ch : bytes) {
    crc ^= static_cast<unsigned char>(ch);
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

struct Chunk {
  std::string type;
  std::string data;
  std::uint32_t crc = 0;
};

std::vector<Chunk> chunks_of(const std::string& png) {
  std::vector<Chunk> chunks;
  std::size_t at = 8;
  while (at + 12 <= png.size()) {
    const std::uint32_t length = read_u32(png, at);
    Chunk chunk;
    chunk.type = png.substr(at + 4, 4);
    chunk.data = png.substr(at + 8, length);
    chunk.crc = read_u32(png, at + 8 + length);
    chunks.push_back(chunk);
    at += 12 + length;
  }
  CHECK(at == png.size());
  return chunks;
}

}  // namespace

TEST_CASE("png_crc32 gives the CRC-32 check value", "[plot]") {
  const std::string check = "123456789";
  CHECK(png_crc32(reinterpret_cast<const std::uint8_t*>(check.data()), check.size()) == 0xCBF43926u);
  CHECK(png_crc32(nullptr, 0) == 0u);
  // Continuing from a previous CRC equals one pass.
  const auto* p = reinterpret_cast<const std::uint8_t*>(check.data());
  CHECK(png_crc32(p + 4, 5, png_crc32(p, 4)) == 0xCBF43926u);
}

TEST_CASE("encode_png writes a valid truecolour PNG", "[plot]") {
  RgbImage image(3, 2, Rgb{10, 20, 30});
  image.set(0, 0, Rgb{255, 0, 0});
  image.set(2, 1, Rgb{0, 0, 255});
  image.set(-1, 0, Rgb{1, 1, 1});  // outside: ignored
  image.set(3, 5, Rgb{1, 1, 1});
  const std::string png = encode_png(image);

  REQUIRE(png.size() > 8);
  CHECK(png.substr(0, 8) == std::string("\x89PNG\r\n\x1a\n", 8));
  const std::vector<Chunk> chunks = chunks_of(png);
  REQUIRE(chunks.size() == 3);
  CHECK(chunks[0].type == "IHDR");
  CHECK(chunks[1].type == "IDAT");
  CHECK(chunks[2].type == "IEND");
  for (const Chunk& chunk : chunks) CHECK(chunk.crc == slow_crc32(chunk.type + chunk.data));

  const std::string& ihdr = chunks[0].data;
  REQUIRE(ihdr.size() == 13);
  CHECK(read_u32(ihdr, 0) == 3);
  CHECK(read_u32(ihdr, 4) == 2);
  CHECK(ihdr[8] == 8);   // bit depth
  CHECK(ihdr[9] == 2);   // truecolour
  CHECK(ihdr[10] == 0);  // deflate
  CHECK(ihdr[11] == 0);  // filter method
  CHECK(ihdr[12] == 0);  // no interlace
  CHECK(chunks[2].data.empty());

  // zlib stream: header CMF/FLG valid (multiple of 31), and inflating it gives filter byte 0 + RGB per row.
  const std::string& idat = chunks[1].data;
  REQUIRE(idat.size() > 6);
  CHECK((static_cast<unsigned char>(idat[0]) & 0x0F) == 8);  // deflate
  CHECK((static_cast<unsigned>(static_cast<unsigned char>(idat[0])) * 256 + static_cast<unsigned char>(idat[1])) % 31 == 0);
  std::vector<unsigned char> raw(2 * (1 + 3 * 3));
  uLongf raw_size = raw.size();
  REQUIRE(uncompress(raw.data(), &raw_size, reinterpret_cast<const Bytef*>(idat.data()), idat.size()) == Z_OK);
  REQUIRE(raw_size == raw.size());
  const std::vector<unsigned char> expected = {0, 255, 0, 0, 10, 20, 30, 10, 20, 30,
                                               0, 10, 20, 30, 10, 20, 30, 0, 0, 255};
  CHECK(raw == expected);
  // Adler-32 of the raw data closes the zlib stream (RFC 1950).
  CHECK(read_u32(idat, idat.size() - 4) == adler32(1, raw.data(), static_cast<uInt>(raw.size())));
}

TEST_CASE("degenerate image sizes become 1 x 1", "[plot]") {
  RgbImage image(0, -3, Rgb{1, 2, 3});
  CHECK(image.width() == 1);
  CHECK(image.height() == 1);
  CHECK(image.at(0, 0) == Rgb{1, 2, 3});
}

TEST_CASE("text draws inside its measured box", "[plot]") {
  RgbImage image(100, 30, Rgb{255, 255, 255});
  const std::string text = "F4 (kPa) 7.5";
  draw_text(image, 2, 3, text, Rgb{0, 0, 0}, 1);
  const int w = text_width(text, 1);
  CHECK(w == 12 * 6 - 1);
  int inked = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) {
      if (image.at(x, y) == Rgb{255, 255, 255}) continue;
      ++inked;
      CHECK(x >= 2);
      CHECK(x < 2 + w);
      CHECK(y >= 3);
      CHECK(y < 3 + text_height(1));
    }
  CHECK(inked > 50);
  CHECK(text_width("", 2) == 0);
}

TEST_CASE("viridis and ticks", "[plot]") {
  CHECK(viridis(0.0) == Rgb{68, 1, 84});
  CHECK(viridis(1.0) == Rgb{253, 231, 37});
  CHECK(viridis(-3.0) == viridis(0.0));
  CHECK(viridis(7.0) == viridis(1.0));
  CHECK(viridis(std::nan("")) == Rgb{160, 160, 160});
  CHECK(nice_ticks(0, 75, 6) == std::vector<double>{0, 10, 20, 30, 40, 50, 60, 70});
  CHECK(nice_ticks(5.3, 22.9, 6) == std::vector<double>{6, 8, 10, 12, 14, 16, 18, 20, 22});
  CHECK(nice_ticks(3, 3, 6) == std::vector<double>{3});
  CHECK(nice_ticks(0, std::numeric_limits<double>::infinity(), 6) == std::vector<double>{0});
}

TEST_CASE("a heat map colours each grid cell by its value on the shared scale", "[plot]") {
  HeatMap map;
  map.x = {0, 1};
  map.y = {0, 1};
  map.z = {0.0, 1.0, 2.0, std::nan("")};  // row 0 (bottom): 0, 1; row 1 (top): 2, NaN
  map.z_min = 0;
  map.z_max = 4;  // a wider scale than the data: 2 is mid-scale
  map.x_label = "x";
  map.y_label = "y";
  map.z_label = "z";
  const RgbImage image = render_heat_map(map);
  CHECK(image.width() == 640);
  CHECK(image.height() == 540);
  const int q1 = kPlotLeft + kPlotSize / 4, q3 = kPlotLeft + 3 * kPlotSize / 4;
  const int top = kPlotTop + kPlotSize / 4, bottom = kPlotTop + 3 * kPlotSize / 4;
  CHECK(image.at(q1, bottom) == viridis(0.0));
  CHECK(image.at(q3, bottom) == viridis(0.25));
  CHECK(image.at(q1, top) == viridis(0.5));
  CHECK(image.at(q3, top) == viridis(std::nan("")));
}
