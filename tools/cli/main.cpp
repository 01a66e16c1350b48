// stipple — host command-line tool: encode scans, inspect and sample `.spg`
// files, measure geometric error, render. One table below drives both the
// dispatch and `stipple --help`.
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "core/protocol.h"
#include "core/spg_format.h"
#include "tools/cli/cli.h"

namespace {

struct Command {
  const char* name;
  const char* summary;
  int (*run)(int argc, char** argv);
};

const Command kCommands[] = {
    {"demo", "encode the bundled scan, render it with the fixed-point client (the main job)", stipple::cmd_demo},
    {"encode", "scan (PLY, PCD, LAS or x y z text) -> .spg", stipple::cmd_encode},
    {"encode-part", "one job of an encode --plan-only plan (for a cluster)", stipple::cmd_encode_part},
    {"info", "describe a .spg file", stipple::cmd_info},
    {"convert", "write a .spg as version 2 (records plain) or 3 (records coded)", stipple::cmd_convert},
    {"sample", "generate points from a .spg cut (reference decoder) -> .ply", stipple::cmd_sample},
    {"metrics", "nearest-neighbour error and PSNR between two point sets", stipple::cmd_metrics},
    {"levels", "bits per point and PSNR of each tree level's cut (the trade)", stipple::cmd_levels},
    {"render", "draw a .spg with the fixed-point handheld client -> .png", stipple::cmd_render},
    {"cut", "the view-dependent cut along an orbit: nodes, culling, bytes of change", stipple::cmd_cut},
    {"cut-table", "write MODEL.spg.cut, the cut bounds servers and viewers map at start", stipple::cmd_cut_table},
    {"serve", "serve a model's view-dependent cuts to clients over TCP", stipple::cmd_serve},
    {"load", "many orbiting viewers against a server: cameras answered, latency", stipple::cmd_load},
    {"ppn-table", "measure the points-per-node table with the client's rasterizer", stipple::cmd_ppn_table},
    {"rd", "rate against distortion across encoder settings, level by level: CSV and plot", stipple::cmd_rd},
    {"trade", "sweep the client's knobs: frame time and error against the reference, CSV and plot", stipple::cmd_trade},
    {"truth", "draw the original scan with render's camera and lighting: the reference picture", stipple::cmd_truth},
    {"image-diff", "compare two PNG images: bytes, object PSNR, SSIM, dark and outside pixels", stipple::cmd_image_diff},
    {"image-crc", "CRC-32 of PNG images' pixels (what stipple-handheld --crc prints)", stipple::cmd_image_crc},
};

void usage(std::FILE* out) {
  std::fputs("usage: stipple <command> [options]\n\n"
             "Statistical point geometry: scans -> hierarchy of Gaussians -> 13/17-byte nodes.\n\ncommands:\n",
             out);
  for (const Command& c : kCommands) std::fprintf(out, "  %-10s %s\n", c.name, c.summary);
  std::fputs("\n`stipple <command> --help` or `stipple help <command>` describes each command;\n"
             "`stipple --version` prints the version.\n", out);
}

// What the command was working on, for a message that must name it: the
// first argument that is not an option.
std::string subject(int argc, char** argv) {
  for (int i = 2; i < argc; ++i)
    if (argv[i][0] != '-') return argv[i];
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 2 && (!std::strcmp(argv[1], "--version") || !std::strcmp(argv[1], "version"))) {
    std::printf("stipple %s (.spg format %u, reads %u to %u; node stream protocol %u)\n", STIPPLE_VERSION,
                unsigned{stipple::kSpgVersion}, unsigned{stipple::kSpgOldestVersion}, unsigned{stipple::kSpgVersion},
                unsigned{stipple::kProtocolVersion});
    return 0;
  }
  // `stipple help VERB` is `stipple VERB --help`.
  if (argc == 3 && !std::strcmp(argv[1], "help")) {
    for (const Command& c : kCommands)
      if (!std::strcmp(argv[2], c.name)) {
        char help[] = "--help";
        char* args[] = {argv[0], argv[2], help, nullptr};
        return c.run(3, args);
      }
    std::fprintf(stderr, "stipple: help: unknown command '%s'\n\n", argv[2]);
    usage(stderr);
    return 2;
  }
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
    usage(argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  for (const Command& c : kCommands) {
    if (std::strcmp(argv[1], c.name) != 0) continue;
    // Errors are values everywhere below; what still escapes (the host ran
    // out of memory, a library threw) ends with a message, never an abort.
    // Appended, not "a" + b: GCC 12 at -O3 warns on that (-Wrestrict, a false positive).
    std::string what = c.name;
    if (const std::string s = subject(argc, argv); !s.empty()) what.append(" ").append(s);
    try {
      return c.run(argc, argv);
    } catch (const std::bad_alloc&) {
      std::fprintf(stderr, "stipple: %s: out of memory (lower --max-points, or use a host with more memory)\n",
                   what.c_str());
    } catch (const std::exception& e) {
      std::fprintf(stderr, "stipple: %s: %s\n", what.c_str(), e.what());
    }
    return 1;
  }
  std::vector<std::string> names;
  for (const Command& c : kCommands) names.emplace_back(c.name);
  const std::string near = stipple::cli::nearest(argv[1], names);
  std::fprintf(stderr, "stipple: unknown command '%s'%s\n\n", argv[1],
               near.empty() ? "" : (" (did you mean '" + near + "'?)").c_str());
  usage(stderr);
  return 2;
}
