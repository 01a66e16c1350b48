// stipple — options shared by the commands that render (render, demo).
#pragma once

#include <string>
#include <vector>

#include "tools/cli/cli.h"
#include "tools/embedded/render_options.h"
#include "tools/reference/render.h"

namespace stipple {

// `--legend`: a panel beside the picture that says what its colours mean —
// the elevation ramp with the heights at its ends (along the view's up
// axis, in the scan's units), the intensity ramp, or the LAS classes.
enum class Legend { kNone, kElevation, kIntensity, kClassification };
// "elevation", "intensity" or "classification"; false with the message.
bool parse_legend(const std::string& text, Legend& out, std::string& error);

// Renders `file` (a whole .spg named `name`) and writes `output` (PNG) when
// not empty, with `legend` beside the picture; prints a summary. Returns
// the process exit code.
int render_to_png(const std::string& name, const std::vector<uint8_t>& file, const RenderOptions& options,
                  const std::string& output, bool reference, bool psnr, bool json, int frames = 1,
                  Legend legend = Legend::kNone);

}  // namespace stipple
