// stipple server — how long a client waits over an emulated link: a server
// and a client in one process joined by a shaped pipe (platform/shaper),
// on the pipe's simulated clock. For the figures of docs/protocol.md and the
// benchmarks; deterministic.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.h"
#include "platform/shaper/shaped_pipe.h"
#include "raster/client.h"

namespace stipple {

struct LinkTiming {
  double first_image_s = 0;  // from the hello to the first node batch applied (something to draw)
  // To the first drawn frame (sampled every 50 ms of link time) covering at
  // least 90 % of the pixels the converged frame covers: a whole silhouette.
  double silhouette_s = 0;
  double converged_s = 0;    // to the update-end of the first camera (the whole cut)
  double orbit_step_s = 0;   // mean time from a camera update to its update-end, over the orbit
  uint64_t bytes_down = 0;   // server -> client, all of it
  uint64_t converged_bytes = 0;   // to the first view's update-end
  double orbit_step_bytes = 0;    // mean, per orbit step
  uint32_t cut_nodes = 0;
  std::vector<double> coverage;  // the share of the converged silhouette drawn, every 50 ms from the hello
};

// The first camera is `cameras[0]`; the rest are the orbit. `coded`: the
// client asks for entropy-coded batches (protocol 5), else compact ones.
bool time_over_link(const std::vector<uint8_t>& file, const LinkProfile& down, const LinkProfile& up,
                    const ClientConfig& config, const std::vector<Camera>& cameras, LinkTiming& out, std::string& error,
                    bool coded = true);

}  // namespace stipple
