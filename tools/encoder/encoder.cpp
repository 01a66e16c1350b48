// stipple host — encoder pipeline; the file is written by core/spg_writer (docs/format.md).
#include "tools/encoder/encoder.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <cstring>

#include "core/spg_format.h"
#include "core/spg_writer.h"
#include "platform/file_io.h"
#include "tools/embedded/options.h"
#include "tools/encoder/classify.h"
#include "tools/encoder/normals.h"
#include "tools/encoder/parallel.h"
#include "tools/encoder/quantize.h"
#include "tools/scan/ply_io.h"

namespace stipple {
namespace {

uint32_t f32_bits(float f) {
  uint32_t bits;
  std::memcpy(&bits, &f, 4);
  return bits;
}

}  // namespace

Vec3 stored_origin(const std::vector<Vec3>& points, int version) {
  if (version < 2 || points.empty()) return Vec3::Zero();
  const Box3 box = bounding_box(points);
  const double extent = (box.max - box.min).maxCoeff();
  const double far = std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff());
  return far > 1024 * extent ? Vec3((box.min + box.max) / 2) : Vec3::Zero();
}

void stored_bounding_box(const std::vector<Vec3>& points, const Vec3& origin, float min[3], float max[3]) {
  const Box3 box = bounding_box(points);
  for (int a = 0; a < 3; ++a) {
    const double l = box.min[a] - origin[a], h = box.max[a] - origin[a];
    float lo = static_cast<float>(l), hi = static_cast<float>(h);
    if (static_cast<double>(lo) > l) lo = std::nextafter(lo, -INFINITY);
    if (static_cast<double>(hi) < h) hi = std::nextafter(hi, INFINITY);
    min[a] = lo;
    max[a] = hi;
  }
}

ScanFrame prepare_scan(PointCloud& cloud, const EncodeOptions& o, const std::function<void(double, const char*)>& progress) {
  const bool estimate = o.normals && !cloud.has_normals();
  if (estimate && !cloud.triangles.empty()) estimate_normals(cloud, o.normal_neighbours, ScanFrame{}, progress, o.tree.threads);
  OrientOptions orient = o.orient;
  if (cloud.has_viewpoint && !orient.has_viewpoint) {  // the file's sensor position, unless an option gives one
    orient.has_viewpoint = true;
    orient.viewpoint = cloud.viewpoint;
  }
  const ScanFrame frame = analyse_scan(cloud.positions, orient, cloud.has_normals() ? &cloud.normals : nullptr);
  if (estimate && !cloud.has_normals()) estimate_normals(cloud, o.normal_neighbours, frame, progress, o.tree.threads);
  return frame;
}

bool encode_cloud(PointCloud& cloud, const EncodeOptions& o, std::vector<uint8_t>& spg, EncodeReport& report,
                  std::string& error, ProgressBar* progress) {
  if (o.classes_p < 0 || o.classes_p > 4096) return error = "--classes: sigma_p classes must be 1..4096", false;
  if (o.classes_n < 0 || o.classes_n > 4096) return error = "--classes: sigma_n classes must be 1..4096", false;
  if (o.classes_c < 0 || o.classes_c > 64) return error = "--classes: sigma_c classes must be 1..64", false;
  if (o.format_version < kSpgOldestVersion || o.format_version > kSpgVersion)
    return error = "--format-version: expected " + std::to_string(kSpgOldestVersion) + " or " + std::to_string(kSpgVersion), false;
  if (o.tree.leaf_size < 2) return error = "--leaf-size must be at least 2", false;
  if (!(o.tree.balance >= 0 && o.tree.balance <= 0.5)) return error = "--balance must be in [0, 0.5]", false;
  if (cloud.size() == 0) return error = "the scan has no points", false;
  if (cloud.size() > 0xFFFFFFFFu) return error = "the scan has more than 2^32-1 points", false;
  if (std::string what = beyond_float_range(cloud.positions); !what.empty()) return error = "the scan's " + what, false;

  report = EncodeReport{};
  report.points = cloud.size();
  const bool normals = o.normals;
  const bool colors = o.colors && cloud.has_colors();
  report.colors = colors;
  report.normals_source = !normals ? "none" : cloud.has_normals() ? "file" : !cloud.triangles.empty() ? "faces" : "k-NN";
  // Progress: normal estimation (when needed) takes the first 30 %, the
  // hierarchy up to 85 %, classification and writing the rest.
  const bool estimate = normals && !cloud.has_normals();
  const double tree_start = estimate ? 0.3 : 0.02;
  // Normals the scan brings (file, faces) are evidence for the rules; faces
  // give theirs first.
  const auto normals_progress = [&](double f, const char* phase) {
    if (progress) progress->update(0.3 * f, phase);
  };
  double stage_start = monotonic_seconds();
  const auto stage_done = [&stage_start](double& seconds) {
    const double now = monotonic_seconds();
    seconds = now - stage_start;
    stage_start = now;
  };
  report.frame = prepare_scan(cloud, o, normals_progress);
  stage_done(report.seconds.normals);
  if (!normals) cloud.normals.clear();
  if (!colors) cloud.colors.clear();

  float bmin[3], bmax[3];  // relative to the origin
  const Vec3 origin = stored_origin(cloud.positions, o.format_version);
  stored_bounding_box(cloud.positions, origin, bmin, bmax);
  double diag = 0;
  for (int a = 0; a < 3; ++a) diag += (double(bmax[a]) - bmin[a]) * (double(bmax[a]) - bmin[a]);
  diag = std::sqrt(diag);

  TreeOptions tree_options = o.tree;
  tree_options.stats.normals = normals;
  tree_options.stats.colors = colors;
  tree_options.stats.sigma_floor = 1e-15 * std::max(diag, 1e-30);
  const auto tree_progress = [&](double f) {
    if (progress) progress->update(tree_start + (0.85 - tree_start) * f, "building hierarchy");
  };
  const Tree tree = o.consume_scan ? build_tree_consuming(cloud, tree_options, tree_progress)
                                   : build_tree(cloud, tree_options, tree_progress);
  report.nodes = tree.nodes.size();
  report.leaves = tree.leaf_count();
  report.depth = tree.depth;
  report.ratios = partition_ratios(tree);
  report.tree = tree.report;
  stage_done(report.seconds.hierarchy);

  // Classes.
  if (progress) progress->update(0.85, "classifying sigmas");
  const size_t n = tree.nodes.size();
  std::vector<Vec3> sp(n), sn(normals ? n : 0), sc(colors ? n : 0);
  for (size_t i = 0; i < n; ++i) {
    const NodeStats& s = tree.nodes[i].stats;
    sp[i] = s.position.sigma;
    if (normals) sn[i] = Vec3(s.sigma_n[0], s.sigma_n[1], 0);
    if (colors) sc[i] = s.color.sigma;
  }
  const int threads = o.tree.threads;
  const int auto_classes = static_cast<int>(std::clamp<size_t>(n / 16, 64, 4096));
  const int classes_p = o.classes_p ? o.classes_p : auto_classes;
  const int classes_n = o.classes_n ? o.classes_n : auto_classes;
  const int classes_c = o.classes_c ? o.classes_c : 64;
  const Classification cp = classify_sigmas(sp, 3, classes_p, 20, threads);
  Classification cn, cc;
  if (normals) cn = classify_sigmas(sn, 2, classes_n, 20, threads);
  if (colors) cc = classify_sigmas(sc, 3, classes_c, 20, threads);
  report.classes[0] = static_cast<int>(cp.centers.size());
  report.classes[1] = static_cast<int>(cn.centers.size());
  report.classes[2] = static_cast<int>(cc.centers.size());
  report.class_rms_log_error[0] = cp.rms_log_error;
  report.class_rms_log_error[1] = cn.rms_log_error;
  report.class_rms_log_error[2] = cc.rms_log_error;
  stage_done(report.seconds.classes);

  // Layout: the thinnest axis gets 10 position bits.
  int thin = 0;
  for (int a = 1; a < 3; ++a)
    if (double(bmax[a]) - bmin[a] < double(bmax[thin]) - bmin[thin]) thin = a;
  const RecordLayout layout = paper_layout(normals, colors, thin);
  const uint16_t flags = static_cast<uint16_t>((normals ? kAttrNormals : 0) | (colors ? kAttrColor : 0));

  if (progress) progress->update(0.95, "writing");
  SpgHeader header;
  header.version = static_cast<uint16_t>(o.format_version);
  header.flags = flags;
  header.tree_arity = tree.octree ? 8 : 2;
  header.layout = layout;
  header.node_count = static_cast<uint32_t>(n);
  header.leaf_count = static_cast<uint32_t>(report.leaves);
  header.point_count = static_cast<uint32_t>(report.points);
  header.depth = static_cast<uint16_t>(tree.depth);
  header.view_hint = report.frame.hint;
  for (int a = 0; a < 3; ++a) {
    header.bbox_bits[a] = f32_bits(bmin[a]);
    header.bbox_bits[3 + a] = f32_bits(bmax[a]);
    std::memcpy(&header.origin_bits[a], &origin[a], 8);
  }
  header.class_count[0] = static_cast<uint16_t>(cp.centers.size());
  header.class_count[1] = static_cast<uint16_t>(cn.centers.size());
  header.class_count[2] = static_cast<uint16_t>(cc.centers.size());
  // Class tables: float32 (version 1) or 16-bit codes, sigma_p relative to
  // the stored box's largest side (docs/format.md §2).
  const bool float_tables = header.version == 1;
  double largest = 0;
  for (int a = 0; a < 3; ++a) largest = std::max(largest, double(bmax[a]) - double(bmin[a]));
  if (!(largest > 0)) largest = 1;  // one point: as the client's decoder takes it
  std::vector<uint32_t> sigma_p, sigma_n, sigma_c;
  for (const Vec3& c : cp.centers)
    for (int d = 0; d < 3; ++d) sigma_p.push_back(float_tables ? f32_bits(static_cast<float>(c[d])) : sigma_p_code(c[d], largest));
  for (const Vec3& c : cn.centers)
    for (int d = 0; d < 2; ++d) sigma_n.push_back(float_tables ? f32_bits(static_cast<float>(c[d])) : q12_code(c[d]));
  for (const Vec3& c : cc.centers)
    for (int d = 0; d < 3; ++d) sigma_c.push_back(float_tables ? f32_bits(static_cast<float>(c[d])) : q12_code(c[d]));
  std::vector<uint8_t> child_counts(n);
  std::vector<uint32_t> leaf_points;
  for (size_t i = 0; i < n; ++i) {
    child_counts[i] = static_cast<uint8_t>(tree.nodes[i].child_count);
    if (tree.nodes[i].leaf()) leaf_points.push_back(static_cast<uint32_t>(tree.nodes[i].count()));
  }

  // Records.
  const AngleBits fp_bits = frame_bits(layout, Field::kFpTheta, false);
  const AngleBits fn_bits = frame_bits(layout, Field::kFnTheta, false);
  const AngleBits fc_bits = frame_bits(layout, Field::kFcTheta, true);
  const size_t record_bytes = static_cast<size_t>(layout.record_bytes());
  std::vector<uint8_t> records(n * record_bytes);
  // Each record depends on its node alone.
  parallel_for(n, threads, 1024, [&](size_t i) {
    const NodeStats& s = tree.nodes[i].stats;
    NodeFields f;
    for (int a = 0; a < 3; ++a) f.v[a] = quantize_cell(s.position.mean[a] - origin[a], bmin[a], bmax[a], layout.bits[a]);
    const FrameCode fp = encode_frame(s.position.frame, fp_bits);
    f[Field::kFpTheta] = fp.theta;
    f[Field::kFpPhi] = fp.phi;
    f[Field::kFpPsi] = fp.psi;
    f[Field::kSigmaP] = cp.index[i];
    if (normals) {
      const FrameCode fn = encode_frame(s.normal_frame, fn_bits);
      f[Field::kFnTheta] = fn.theta;
      f[Field::kFnPhi] = fn.phi;
      f[Field::kFnPsi] = fn.psi;
      f[Field::kSigmaN] = cn.index[i];
    }
    if (colors) {
      f[Field::kColorR] = quantize_unit(s.color.mean[0], layout.width(Field::kColorR));
      f[Field::kColorG] = quantize_unit(s.color.mean[1], layout.width(Field::kColorG));
      f[Field::kColorB] = quantize_unit(s.color.mean[2], layout.width(Field::kColorB));
      const FrameCode fc = encode_frame(s.color.frame, fc_bits);
      f[Field::kFcTheta] = fc.theta;
      f[Field::kFcPhi] = fc.phi;
      f[Field::kFcPsi] = fc.psi;
      f[Field::kSigmaC] = cc.index[i];
    }
    pack_record(layout, f, records.data() + i * record_bytes);
  });
  const SpgContent content{header, SpgClassTables{sigma_p.data(), sigma_n.data(), sigma_c.data()}, child_counts.data(),
                           leaf_points.data(), records.data()};
  spg.assign(spg_write_bound(header), 0);
  size_t written = 0;
  const SpgWriteStatus status = spg_write(content, spg.data(), spg.size(), &written);
  if (status != SpgWriteStatus::kOk) {
    error = std::string("encoder: ") + spg_write_status_text(status);
    return false;
  }
  spg.resize(written);

  report.bytes = spg.size();
  report.record_bytes = record_bytes;
  report.bits_per_point = 8.0 * static_cast<double>(spg.size()) / static_cast<double>(report.points);
  stage_done(report.seconds.write);
  if (progress) progress->update(1.0, "done");
  return true;
}

bool read_model(const std::string& path, std::vector<uint8_t>& spg, std::string& error) {
  if (!read_file(path, spg, error)) return false;
  if (spg.size() >= 4 && std::memcmp(spg.data(), kSpgMagic, 4) == 0) return true;  // a .spg: validated by its reader
  std::vector<uint8_t> bytes;
  bytes.swap(spg);
  PointCloud cloud;
  if (!parse_point_cloud(path, bytes.data(), bytes.size(), cloud, error)) return false;
  bytes = {};
  for (const std::string& w : cloud.warnings) std::fprintf(stderr, "stipple: warning: %s\n", w.c_str());
  const auto start = std::chrono::steady_clock::now();
  ProgressBar progress("encode " + path, true);
  EncodeReport report;
  EncodeOptions options;
  options.consume_scan = true;  // the scan is not needed after
  if (!encode_cloud(cloud, options, spg, report, error, &progress)) return error = path + ": " + error, false;
  progress.finish();
  // The model's name: the scan's, in the current folder (the scan's own may be read-only).
  std::string stem = path.substr(path.find_last_of('/') + 1);
  if (const size_t dot = stem.find_last_of('.'); dot != std::string::npos && dot > 0) stem.resize(dot);
  std::fprintf(stderr, "stipple: %s: a scan, encoded in memory: %s nodes in %.2f s (stipple encode %s -o %s.spg keeps it)\n",
               path.c_str(), cli::with_commas(report.nodes).c_str(),
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), path.c_str(), stem.c_str());
  return true;
}

}  // namespace stipple
