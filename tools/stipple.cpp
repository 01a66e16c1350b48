// stipple — host command-line tool: encode scans, inspect and sample `.spg`
// files, measure geometric error. `stipple --help` lists the subcommands.
#include <cstdio>
#include <cstring>

#include "tools/cli.h"

namespace {

const char kUsage[] =
    "usage: stipple <command> [options]\n"
    "\n"
    "Statistical point geometry: scans -> hierarchy of Gaussians -> 13/17-byte nodes.\n"
    "\n"
    "commands:\n"
    "  demo      encode the bundled scan, render it with the fixed-point client (the main job)\n"
    "  encode    scan (.ply or x y z text) -> .spg\n"
    "  info      describe a .spg file\n"
    "  sample    generate points from a .spg cut (reference decoder) -> .ply\n"
    "  metrics   nearest-neighbour error and PSNR between two point sets\n"
    "  levels    bits per point and PSNR of each tree level's cut (the trade)\n"
    "  render    draw a .spg with the fixed-point handheld client -> .png\n"
    "  ppn-table measure the points-per-node table with the client's rasterizer\n"
    "  image-diff compare two PNG images byte for byte, write a diff image\n"
    "  image-crc CRC-32 of PNG images' pixels (what stipple-handheld --crc prints)\n"
    "\n"
    "`stipple <command> --help` describes each command.\n";

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
    std::fputs(kUsage, argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const char* command = argv[1];
  if (!std::strcmp(command, "encode")) return stipple::cmd_encode(argc, argv);
  if (!std::strcmp(command, "demo")) return stipple::cmd_demo(argc, argv);
  if (!std::strcmp(command, "info")) return stipple::cmd_info(argc, argv);
  if (!std::strcmp(command, "sample")) return stipple::cmd_sample(argc, argv);
  if (!std::strcmp(command, "metrics")) return stipple::cmd_metrics(argc, argv);
  if (!std::strcmp(command, "levels")) return stipple::cmd_levels(argc, argv);
  if (!std::strcmp(command, "render")) return stipple::cmd_render(argc, argv);
  if (!std::strcmp(command, "ppn-table")) return stipple::cmd_ppn_table(argc, argv);
  if (!std::strcmp(command, "image-diff")) return stipple::cmd_image_diff(argc, argv);
  if (!std::strcmp(command, "image-crc")) return stipple::cmd_image_crc(argc, argv);
  std::fprintf(stderr, "stipple: unknown command '%s'\n\n%s", command, kUsage);
  return 2;
}
