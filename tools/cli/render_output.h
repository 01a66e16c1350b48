// stipple — options shared by the commands that render (render, demo).
#pragma once

#include <string>
#include <vector>

#include "tools/cli/cli.h"
#include "tools/embedded/render_options.h"
#include "tools/reference/render.h"

namespace stipple {

// Renders `file` (a whole .spg named `name`) and writes `output` (PNG) when
// not empty, with `legend` ("elevation", "intensity", "classification": a
// panel beside the picture saying what its colours mean; "": none); prints
// a summary. Returns the process exit code.
int render_to_png(const std::string& name, const std::vector<uint8_t>& file, const RenderOptions& options,
                  const std::string& output, bool reference, bool psnr, bool json, int frames = 1,
                  const std::string& legend = "");

}  // namespace stipple
