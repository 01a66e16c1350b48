// stipple host — the trade of a model's tree levels. See level_trade.h.
#include "tools/reference/level_trade.h"

#include "core/spg_format.h"
#include "platform/progress.h"
#include "tools/encoder/coded_file.h"
#include "tools/reference/metrics.h"
#include "tools/reference/sampler.h"

namespace stipple {

bool measure_levels(const DecodedModel& model, const PointCloud& original, const KdTree& original_tree,
                    const std::vector<int>& levels, std::vector<LevelPoint>& out, std::string& error,
                    const std::function<void(size_t)>& progress, const std::vector<uint8_t>* file) {
  const SpgHeader& h = model.header;
  SpgView view;
  const bool coded = file != nullptr && spg_parse(file->data(), file->size(), &view).ok();
  const double startup_bytes = static_cast<double>(spg_startup_bytes(h.version, h.class_count));
  out.clear();
  for (size_t i = 0; i < levels.size(); ++i) {
    if (progress) progress(i);
    const std::vector<uint32_t> cut = level_cut(model, levels[i]);
    const uint64_t limit = default_max_samples(physical_memory_bytes());
    if (cut_sample_count(model, cut, 0) > limit) {
      error = "level " + std::to_string(levels[i]) + " would generate more than " + std::to_string(limit) +
              " points (the limit for this host's memory)";
      return false;
    }
    const CloudMetrics m = compare_clouds(original, original_tree, sample_cut(model, cut, 0));
    LevelPoint p;
    p.level = levels[i];
    p.nodes = cut.size();
    p.bits_per_point = 8.0 * (startup_bytes + static_cast<double>(cut.size()) * h.layout.record_bytes()) /
                       static_cast<double>(original.size());
    if (coded)
      p.coded_bits_per_point = 8.0 * (startup_bytes + static_cast<double>(coded_cut_bytes(view, cut))) /
                               static_cast<double>(original.size());
    p.psnr_one_sided = m.psnr_one_sided;
    p.psnr_symmetric = m.psnr_symmetric;
    p.hausdorff = m.hausdorff;
    out.push_back(p);
  }
  return true;
}

}  // namespace stipple
