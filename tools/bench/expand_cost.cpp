// What a handheld pays, in instructions a node, to open a .spg version 3
// file (docs/format.md §5, "Coded records"): built for ARMv5 by
// tools/bench/expand_cost.sh, it expands MODEL.spg PASSES times; the script
// counts a run of two passes less a run of one under qemu-user.
//   expand_cost MODEL.spg PASSES
// Core only (it runs where the handheld does); prints the nodes and bytes.
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/spg_coded.h"
#include "core/spg_format.h"

int main(int argc, char** argv) {
  if (argc != 3) return std::fprintf(stderr, "usage: expand_cost MODEL.spg PASSES\n"), 2;
  std::vector<uint8_t> file;
  if (std::FILE* f = std::fopen(argv[1], "rb")) {
    uint8_t chunk[65536];
    for (size_t n; (n = std::fread(chunk, 1, sizeof chunk, f)) > 0;) file.insert(file.end(), chunk, chunk + n);
    std::fclose(f);
  }
  stipple::SpgView view;
  stipple::SpgCodedParts parts;
  if (!stipple::spg_parse_coded(file.data(), file.size(), &view, &parts).ok())
    return std::fprintf(stderr, "%s: not a valid .spg version 3\n", argv[1]), 1;
  std::vector<uint8_t> image(stipple::spg_expanded_bytes(view, parts)), points(view.header.node_count);
  const int passes = std::atoi(argv[2]);
  for (int p = 0; p < passes; ++p)
    if (!stipple::spg_expand(file.data(), view, parts, image.data(), points.data()).ok())
      return std::fprintf(stderr, "%s: does not expand\n", argv[1]), 1;
  std::printf("%s: %u nodes, %zu bytes expanded to %zu\n", argv[1], view.header.node_count, file.size(), image.size());
  return 0;
}
