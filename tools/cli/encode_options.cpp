// stipple encode and demo — their shared options and summary.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>

#include "platform/file_io.h"
#include "platform/progress.h"
#include "tools/cli/cli.h"
#include "tools/cli/encode_options.h"
#include "tools/cli/render_output.h"
#include "tools/encoder/encoder.h"
#include "tools/encoder/normals.h"
#include "tools/reference/metrics.h"
#include "tools/reference/sampler.h"
#include "tools/reference/spg_model.h"
#include "tools/scan/ply_io.h"

namespace stipple {

bool parse_encode_options(cli::Args& args, EncodeOptions& o, bool& quiet, bool& json, std::string& error) {
  std::string v;
  unsigned long long u;
  const bool leaf_size = args.value("--leaf-size", v);
  if (leaf_size) {
    if (!cli::parse_uint(v, 1u << 20, u) || u < 2) return error = "--leaf-size: expected an integer >= 2, got '" + v + "'", false;
    o.tree.leaf_size = static_cast<uint32_t>(u);
  }
  if (args.value("--tolerance", v)) {
    // A length in the scan's units, one with a unit (the scan in metres),
    // or a percentage of the bounding box's diagonal.
    struct Unit {
      const char* suffix;
      double scale;
    };
    static constexpr Unit kUnits[] = {{"um", 1e-6}, {"mm", 1e-3}, {"cm", 1e-2}, {"m", 1.0}, {"%", 1e-2}};
    double scale = 1;
    std::string number = v;
    bool relative = false;
    for (const Unit& unit : kUnits) {
      const size_t n = std::char_traits<char>::length(unit.suffix);
      if (number.size() > n && number.compare(number.size() - n, n, unit.suffix) == 0) {
        number.resize(number.size() - n);
        scale = unit.scale;
        relative = unit.suffix[0] == '%';
        break;
      }
    }
    double t = 0;
    if (!cli::parse_double(number, t) || !(t > 0) || (relative && t > 100))
      return error = "--tolerance: expected a length (0.002, 2mm, 0.5cm) or a share of the diagonal (0.3%), got '" + v + "'", false;
    o.tolerance = t * scale;
    o.tolerance_relative = relative;
    if (!leaf_size) o.tree.leaf_size = 2;  // the variance stop decides where leaves are
  }
  if (args.value("--classes", v)) {
    unsigned long long c[3];
    size_t start = 0;
    for (int k = 0; k < 3; ++k) {
      const size_t comma = v.find(',', start);
      const std::string part = v.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      if (!cli::parse_uint(part, ~0ull, c[k]) || (k < 2 && comma == std::string::npos) ||
          (k == 2 && comma != std::string::npos))
        return error = "--classes: expected P,N,C (three integers), got '" + v + "'", false;
      start = comma + 1;
    }
    // In range, or named: the count at fault and its range (0 is automatic).
    const char* names[3] = {"P (sigma_p classes)", "N (sigma_n classes)", "C (sigma_c classes)"};
    const unsigned long long most[3] = {4096, 4096, 64};
    for (int k = 0; k < 3; ++k)
      if (c[k] > most[k])
        return error = "--classes: " + std::string(names[k]) + " is " + std::to_string(c[k]) + ", beyond 0.." +
                       std::to_string(most[k]) + " (0: chosen from the scan)",
               false;
    o.classes_p = static_cast<int>(c[0]);
    o.classes_n = static_cast<int>(c[1]);
    o.classes_c = static_cast<int>(c[2]);
  }
  if (args.value("--balance", v)) {
    if (!cli::parse_double(v, o.tree.balance) || o.tree.balance < 0 || o.tree.balance > 0.5)
      return error = "--balance: expected a number in [0, 0.5], got '" + v + "'", false;
  }
  if (args.value("--shrink", v)) {
    const size_t comma = v.find(',');
    if (comma == std::string::npos || !cli::parse_double(v.substr(0, comma), o.tree.stats.shrink_eta0) ||
        !cli::parse_double(v.substr(comma + 1), o.tree.stats.shrink_eta1) || o.tree.stats.shrink_eta0 < 0 ||
        o.tree.stats.shrink_eta0 > 1 || o.tree.stats.shrink_eta1 < 0)
      return error = "--shrink: expected ETA0,ETA1 with ETA0 in [0, 1] and ETA1 >= 0, got '" + v + "'", false;
  }
  if (args.value("--neighbours", v)) {
    if (!cli::parse_uint(v, 64, u) || u < 3) return error = "--neighbours: expected 3..64, got '" + v + "'", false;
    o.normal_neighbours = static_cast<int>(u);
  }
  if (!parse_threads(args, o.tree.threads, error)) return false;
  if (args.value("--memory", v) && (!parse_bytes(v, o.memory) || o.memory < (uint64_t{64} << 20)))
    return error = "--memory: expected a size of at least 64M (as 2G, 1500M, 2147483648), got '" + v + "'", false;
  if (args.value("--partition-points", v)) {
    if (!cli::parse_uint(v, 0xFFFFFFFFull, u) || u < 1024)
      return error = "--partition-points: expected 1024..4294967295, got '" + v + "'", false;
    o.partition_points = u;
  }
  args.value("--tmp", o.tmp_dir);
  if (args.value("--class-sample", v)) {
    if (!cli::parse_uint(v, 1ull << 32, u) || u < 4096)
      return error = "--class-sample: expected 4096..4294967296 nodes, got '" + v + "'", false;
    o.class_sample = u;
  }
  if (!parse_orient_options(args, o.orient, error)) return false;
  if (args.value("--up", v) && !spg_parse_axis(v.c_str(), &o.orient.up))
    return error = "--up: expected +x, -x, +y, -y, +z or -z, got '" + v + "'", false;
  if (args.value("--format-version", v)) {
    if (!cli::parse_uint(v, kSpgCodedVersion, u) || u < kSpgOldestVersion)
      return error = "--format-version: expected 1, 2 or 3, got '" + v + "'", false;
    o.coded_file = u == kSpgCodedVersion;
    o.format_version = o.coded_file ? kSpgVersion : static_cast<int>(u);
  }
  if (args.flag("--no-shrink")) o.tree.stats.shrink_eta0 = 1.0;
  o.curvature_sign = !args.flag("--no-curvature-sign");
  o.tree.octree = args.flag("--octree");
  o.normals = !args.flag("--no-normals");
  o.colors = !args.flag("--no-color");
  quiet = args.flag("--quiet") || args.flag("-q");
  json = args.flag("--json");
  o.cut_table = !args.flag("--no-cut-table");
  if (args.bad()) return error = args.error(), false;
  return true;
}

bool parse_orient_options(cli::Args& args, OrientOptions& o, std::string& error) {
  std::string v;
  if (args.value("--orient", v)) {
    const OrientMode modes[] = {OrientMode::kAuto, OrientMode::kSensor, OrientMode::kUp, OrientMode::kOutward};
    bool found = false;
    for (OrientMode m : modes)
      if (v == orient_mode_name(m)) o.mode = m, found = true;
    if (!found) return error = "--orient: expected auto, sensor, up or outward, got '" + v + "'", false;
  }
  if (args.value("--viewpoint", v)) {
    double xyz[3];
    if (!cli::parse_vec3(v, xyz)) return error = "--viewpoint: expected X,Y,Z (three finite numbers), got '" + v + "'", false;
    o.has_viewpoint = true;
    o.viewpoint = Vec3(xyz[0], xyz[1], xyz[2]);
  }
  return true;
}

bool parse_threads(cli::Args& args, int& threads, std::string& error) {
  std::string v;
  unsigned long long u = 0;
  if (!args.value("--threads", v)) {
    threads = static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 256u));  // every core
    return true;
  }
  if (!cli::parse_uint(v, 256, u) || u < 1) return error = "--threads: expected 1..256, got '" + v + "'", false;
  threads = static_cast<int>(u);
  return true;
}

bool parse_bytes(const std::string& text, uint64_t& bytes) {
  size_t digits = 0;
  while (digits < text.size() && std::isdigit(static_cast<unsigned char>(text[digits]))) ++digits;
  unsigned long long value = 0;
  if (digits == 0 || digits > 15 || !cli::parse_uint(text.substr(0, digits), 1ull << 50, value)) return false;
  std::string unit = text.substr(digits);
  for (char& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (unit.size() > 1 && unit.back() == 'B') unit.pop_back();  // 2GB, 2GiB
  if (unit.size() == 2 && unit[1] == 'I') unit.pop_back();
  const int shift = unit.empty() ? 0 : unit == "K" ? 10 : unit == "M" ? 20 : unit == "G" ? 30 : unit == "T" ? 40 : -1;
  if (shift < 0 || value > (uint64_t{1} << (62 - shift))) return false;
  bytes = uint64_t{value} << shift;
  return true;
}

std::string summary_json(const std::string& scan, const EncodeReport& r, double seconds, double peak_mb) {
  cli::Json j;
  j.str("scan", scan)
      .integer("points", static_cast<long long>(r.points))
      .integer("nodes", static_cast<long long>(r.nodes))
      .integer("leaves", static_cast<long long>(r.leaves))
      .integer("depth", r.depth)
      .integer("partitions", r.partitions)
      .integer("bytes", static_cast<long long>(r.bytes))
      .integer("record_bytes", static_cast<long long>(r.record_bytes))
      .num("bits_per_point", r.bits_per_point)
      .num("seconds", seconds)
      .num("peak_mb", peak_mb)
      .str("normals", r.normals_source)
      .str("scan_kind", scan_kind_name(r.frame.kind))
      .str("orient", orient_mode_name(r.frame.orient))
      .str("view_up", spg_axis_name(r.frame.hint.up))
      .str("view_sensor_side", spg_axis_name(r.frame.hint.sensor_side))
      .boolean("colors", r.colors)
      .integer("classes_p", r.classes[0])
      .integer("classes_n", r.classes[1])
      .integer("classes_c", r.classes[2])
      .num("class_rms_log_error_p", r.class_rms_log_error[0])
      .num("class_rms_log_error_n", r.class_rms_log_error[1])
      .num("class_rms_log_error_c", r.class_rms_log_error[2])
      .num("apr", r.ratios.apr)
      .num("capr", r.ratios.capr)
      .integer("capr_excluded", static_cast<long long>(r.ratios.capr_excluded))
      .integer("euclidean_fallbacks", static_cast<long long>(r.tree.euclidean_fallbacks))
      .integer("unbalanced_splits", static_cast<long long>(r.tree.unbalanced))
      .num("read_seconds", r.seconds.read)
      .num("plan_seconds", r.seconds.plan)
      .num("route_seconds", r.seconds.route)
      .num("normals_seconds", r.seconds.normals)
      .num("hierarchy_seconds", r.seconds.hierarchy)
      .num("classes_seconds", r.seconds.classes)
      .num("write_seconds", r.seconds.write)
      .integer("expanded_bytes", static_cast<long long>(r.expanded_bytes ? r.expanded_bytes : r.bytes))
      .num("coding_seconds", r.seconds.coding)
      .str("cut_table", r.cut_table)
      .integer("cut_table_bytes", static_cast<long long>(r.cut_table_bytes))
      .num("cut_table_seconds", r.seconds.cut_table);
  return j.done();
}

void print_summary(const std::string& scan, const EncodeReport& r, double seconds, double peak_mb) {
  std::printf("%s: %s points, %s nodes, %s leaves, depth %d, %s bytes (%llu-byte records), %.2f bits/point, "
              "%.2f s, peak %.0f MB\n",
              scan.c_str(), cli::with_commas(r.points).c_str(), cli::with_commas(r.nodes).c_str(),
              cli::with_commas(r.leaves).c_str(), r.depth, cli::with_commas(r.bytes).c_str(),
              static_cast<unsigned long long>(r.record_bytes), r.bits_per_point, seconds, peak_mb);
  std::printf("  %s; normals %s%s; view: up %s, sensor side %s\n", r.frame.reason.c_str(), r.normals_source.c_str(),
              r.normals_source == "k-NN" ? (std::string(", facing ") + orient_mode_name(r.frame.orient)).c_str() : "",
              spg_axis_name(r.frame.hint.up), spg_axis_name(r.frame.hint.sensor_side));
  if (r.partitions > 1) std::printf("  in %u partitions (tools/encoder/partition.h)\n", r.partitions);
  if (r.expanded_bytes > 0)
    std::printf("  version 3: records coded, %s bytes as version 2 (-%.1f %%), %.2f s\n",
                cli::with_commas(r.expanded_bytes).c_str(),
                100.0 * (1.0 - static_cast<double>(r.bytes) / static_cast<double>(r.expanded_bytes)), r.seconds.coding);
  if (!r.cut_table.empty())
    std::printf("  cut table %s, %s bytes, %.2f s\n", r.cut_table.c_str(), cli::with_commas(r.cut_table_bytes).c_str(),
                r.seconds.cut_table);
}

void keep_every(PointCloud& cloud, unsigned long long k, const EncodeOptions& o) {
  if (o.normals) estimate_normals(cloud, o.normal_neighbours, analyse_scan(cloud.positions, o.orient));
  PointCloud out;
  for (size_t i = 0; i < cloud.size(); i += k) {
    out.positions.push_back(cloud.positions[i]);
    if (cloud.has_normals()) out.normals.push_back(cloud.normals[i]);
    if (cloud.has_colors()) out.colors.push_back(cloud.colors[i]);
  }
  cloud = std::move(out);
}

}  // namespace stipple
