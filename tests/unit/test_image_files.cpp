// Image output chosen by extension: .png (8-bit sRGB) or .exr (linear float).
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>

#include <catch2/catch.hpp>
#include <filesystem>

#include "../common/temp_files.hpp"
#include "prt/error.hpp"
#include "prt/image.hpp"
#include "prt/output_file.hpp"

using namespace prt;
using Catch::Contains;
namespace fs = std::filesystem;

TEST_CASE("renders are written as OpenEXR linear floats or PNG, by extension", "[image]") {
  const fs::path dir = test::fresh_dir("prt_images_", "exr");
  Image image(5, 3);
  for (std::size_t i = 0; i < image.rgb.size(); ++i)
    image.rgb[i] = 0.001f * float(i * i) + (i == 7 ? 1234.5f : 0.f);  // beyond 1: HDR
  write_image(image, dir / "render.exr", 0.25f);                      // exposure is for PNGs only
  CHECK(detect_file_kind(dir / "render.exr") == FileKind::exr);

  Imf::InputFile in((dir / "render.exr").string().c_str());
  const Imath::Box2i window = in.header().dataWindow();
  REQUIRE(window.max.x - window.min.x + 1 == 5);
  REQUIRE(window.max.y - window.min.y + 1 == 3);
  CHECK(in.header().channels().findChannel("R")->type == Imf::FLOAT);
  std::vector<float> back(image.rgb.size());
  Imf::FrameBuffer frame;
  for (int c = 0; c < 3; ++c)
    frame.insert(c == 0   ? "R"
                 : c == 1 ? "G"
                          : "B",
                 Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(back.data() + c), 3 * sizeof(float),
                            15 * sizeof(float)));
  in.setFrameBuffer(frame);
  in.readPixels(window.min.y, window.max.y);
  CHECK(back == image.rgb);  // bit for bit, top row first

  write_image(image, dir / "render.PNG");
  CHECK(detect_file_kind(dir / "render.PNG") == FileKind::png);
  CHECK_THROWS_WITH(
      write_image(image, dir / "render.jpg"),
      Contains("render.jpg") && Contains("unknown image type \".jpg\"") && Contains(".exr"));
  CHECK_FALSE(fs::exists(dir / "render.jpg"));
  CHECK_THROWS_WITH(write_exr(Image(0, 0), dir / "empty.exr"), Contains("0 x 0"));
  CHECK_FALSE(fs::exists(dir / "empty.exr"));
}
