// stipple image-crc — the CRC-32 of images' pixels (what stipple-handheld --crc prints).
#include <cstdio>
#include <string>
#include <vector>

#include "core/spg_format.h"
#include "platform/png_io.h"
#include "tools/cli/cli.h"

namespace stipple {

int cmd_image_crc(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs("usage: stipple image-crc IMAGE.png...\n"
               "\n"
               "Prints the CRC-32 of each image's RGB888 pixel bytes (rows top to bottom, no\n"
               "header) — what `stipple-handheld --crc` prints for a frame, so a target without\n"
               "libpng can be checked against the golden PNGs (tests/golden/images.crc).\n",
               stdout);
    return 0;
  }
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("image-crc: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("image-crc: " + args.unknown_option_message());
  if (files.empty()) return cli::fail("image-crc: expected one or more PNG files");
  for (const std::string& f : files) {
    Image img;
    std::string error;
    if (!read_png(f, img, error)) return cli::fail(error);
    std::printf("crc32 %08x  %s\n", crc32(img.rgb.data(), img.rgb.size()), f.c_str());
  }
  return 0;
}

}  // namespace stipple
