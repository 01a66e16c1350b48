// stipple encode and demo — the options they share and the summary they print.
#pragma once

#include <string>

#include "tools/cli/cli.h"
#include "tools/encoder/encoder.h"
#include "tools/scan/point_cloud.h"

namespace stipple {

// Parses the options shared by encode and demo. Returns false on a bad value.
bool parse_encode_options(cli::Args& args, EncodeOptions& o, bool& quiet, bool& json, std::string& error);

// --orient and --viewpoint alone (truth takes these; its --up is render's).
bool parse_orient_options(cli::Args& args, OrientOptions& o, std::string& error);

// --threads N (1..256), or one per core.
bool parse_threads(cli::Args& args, int& threads, std::string& error);
// "2G", "1500M", "512KiB", "2147483648": bytes (binary units; B, iB optional).
bool parse_bytes(const std::string& text, uint64_t& bytes);
std::string summary_json(const std::string& scan, const EncodeReport& r, double seconds, double peak_mb);
void print_summary(const std::string& scan, const EncodeReport& r, double seconds, double peak_mb);

// Keeps every k-th point. Normals are derived first, from the full mesh, since
// the subset's triangles would be meaningless.
void keep_every(PointCloud& cloud, unsigned long long k, const EncodeOptions& o);

}  // namespace stipple
