// stipple tools — the render options, parsed once for every program that
// renders through the embedded default (`stipple render`, `stipple demo`,
// `stipple-handheld`): screen, view, cut and client configuration, strictly
// (a value with trailing text is refused, naming the option).
#pragma once

#include <string>

#include "core/cut.h"
#include "raster/client.h"
#include "tools/embedded/embedded.h"
#include "tools/embedded/options.h"

namespace stipple {

struct RenderOptions {
  ClientConfig config;  // 240x320 RGB565, 2^20-point budget unless set
  CutRule rule{CutRule::kProjectedSize, 0, 32};
  ViewSpec view;
  bool sized = false;  // --size was given
  bool tile_nodes_given = false;  // --tile-nodes was given (the handheld's default is kHandheldTileNodes: its arena)
  bool lanes_given = false;       // --lanes was given (the handheld's default is its device's: baseline)
  std::string token;              // --connect: a pre-shared token for a server started with --token
  bool coded = true;              // over a link: entropy-coded node batches (protocol 5); --no-coding
};

// The help lines of these options (view, cut, client), for a program's usage.
extern const char kRenderOptionsHelp[];

// Consumes the options of kRenderOptionsHelp from `args` into `o`; false
// with a message naming the option on a bad value.
bool parse_render_options(cli::Args& args, RenderOptions& o, std::string& error);

// --leaf-cone's value: a multiple of sigma_n1 within [0, 8], as Q8.
bool parse_leaf_cone(const std::string& value, uint16_t& q8, std::string& error);

}  // namespace stipple
