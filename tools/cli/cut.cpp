// stipple cut — the view-dependent cut along a camera orbit: its size, what
// culling removes, and the bytes a server would stream (the change) against
// resending the whole cut each frame (what TOG05 did).
#include <cstdio>
#include <string>
#include <vector>

#include "core/protocol.h"
#include "core/view_cut.h"
#include "platform/file_io.h"
#include "platform/progress.h"
#include "tools/cli/cli.h"
#include "tools/embedded/embedded.h"
#include "tools/embedded/model_file.h"
#include "tools/embedded/render_options.h"

namespace stipple {
namespace {

const char kCutHelp[] =
    "usage: stipple cut MODEL.spg [--orbit N] [--incremental] [--json] [view and cut options]\n"
    "\n"
    "Runs the view-dependent cut (core/view_cut.h) for the view, then for N\n"
    "cameras of an orbit about the up axis (the view's yaw + 360 k / N; default\n"
    "120), and prints: the cold start (nodes sent, culled, bytes), and per orbit\n"
    "step the mean nodes sent, entered and left, the bytes of the change (an\n"
    "entering node costs its id, its point count and record, a leaving one its\n"
    "id: 5 + R and 4 bytes) against resending the whole cut (5 + R a node), and\n"
    "the nodes the\n"
    "update visited. Protocol framing is not counted. The view and cut options\n"
    "are render's: --size, --camera, --up, --max-size, --no-cull, --leaf-cone,\n"
    "--window, --cache (the node budget).\n"
    "\n"
    "  --incremental   update the cut from the previous one (TOG05's persistent\n"
    "                  cut; the server derives each from the root), looking\n"
    "                  again only at nodes whose deadline came; the cut is the\n"
    "                  same, the nodes evaluated per step are printed\n";

const char kCutTableHelp[] =
    "usage: stipple cut-table MODEL.spg [--leaf-cone G] [--check]\n"
    "\n"
    "Writes MODEL.spg.cut beside the model: its per-node cut bounds (36 bytes a\n"
    "node; docs/format.md \"The cut table\"), which stipple serve, the viewers\n"
    "and stipple-handheld map instead of decoding the whole tree when they\n"
    "start, so N servers of a model share one copy in the page cache. stipple\n"
    "encode writes one; this makes one for an older file, or for servers run\n"
    "with another --leaf-cone. A table already there that is the model's is\n"
    "left as it is (\"up to date\").\n"
    "\n"
    "  --leaf-cone G   the leaf cone the table's cones follow (default 1: what\n"
    "                  serve and render use unless told otherwise)\n"
    "  --check         write nothing; exit 1 when the table is missing or is not\n"
    "                  the model's, saying why\n";

}  // namespace

int cmd_cut_table(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) return std::fputs(kCutTableHelp, stdout), 0;
  std::string error, v;
  ConeRule cones;
  if (args.value("--leaf-cone", v) && !parse_leaf_cone(v, cones.leaf_gamma_q8, error)) return cli::fail("cut-table: " + error);
  const bool check = args.flag("--check");
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("cut-table: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("cut-table: " + args.unknown_option_message());
  if (files.size() != 1) return cli::fail("cut-table: expected one .spg file (see stipple cut-table --help)");
  const double start = monotonic_seconds();
  if (check) {
    ModelFile model;
    if (!model.open(files[0], cones, error)) return cli::fail("cut-table: " + error);
    if (!model.table_mapped()) return cli::fail("cut-table: " + model.table_note());
    std::printf("%s: up to date\n", cut_table_path(files[0]).c_str());
    return 0;
  }
  bool written = false;
  if (!make_cut_table(files[0], cones, error, &written)) return cli::fail("cut-table: " + error);
  std::printf("%s: %s in %.2f s\n", cut_table_path(files[0]).c_str(), written ? "written" : "up to date",
              monotonic_seconds() - start);
  return 0;
}

int cmd_cut(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kCutHelp, stdout);
    return 0;
  }
  RenderOptions o;
  std::string error, v;
  if (!parse_render_options(args, o, error)) return cli::fail("cut: " + error);
  unsigned long long steps = 120;
  if (args.value("--orbit", v) && (!cli::parse_uint(v, 100000, steps) || steps == 0))
    return cli::fail("cut: --orbit: expected 1..100000 steps, got '" + v + "'");
  const bool json = args.flag("--json");
  const bool incremental = args.flag("--incremental");
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("cut: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("cut: " + args.unknown_option_message());
  if (files.size() != 1) return cli::fail("cut: expected one .spg file (see stipple cut --help)");
  std::vector<uint8_t> file;
  if (!read_spg_file(files[0], file, error)) return cli::fail(error);
  SpgView view;
  const SpgResult r = spg_parse(file.data(), file.size(), &view);
  if (!r.ok()) return cli::fail(spg_error_message(files[0], r, file.data(), file.size()));
  std::vector<uint8_t> decoder_storage(node_decoder_bytes(view.header));
  NodeDecoder decoder;
  if (decoder.init(view, decoder_storage.data(), decoder_storage.size()) != DecodeStatus::kOk)
    return cli::fail(files[0] + ": the angle fields are wider than the decoder supports");
  std::vector<uint64_t> storage(view_cut_bytes(view.header) / 8 + 1);
  ViewCut cut;
  if (cut.init(view, decoder, storage.data(), storage.size() * 8, cone_rule(o.rule)) != CutStatus::kOk)
    return cli::fail("cut: init failed");
  std::vector<uint64_t> front;
  if (incremental) {
    front.resize(ViewCut::front_bytes(view.header.node_count) / 8 + 1);
    cut.use_front(front.data(), front.size() * 8);
  }
  const CutParams p = cut_params(o.rule, o.config);
  const ViewSpec base = resolve_view(o.view, view.header, decoder.extent_mu());
  const auto camera_at = [&](double yaw, Camera& c) {
    ViewSpec s = base;
    s.yaw = yaw;
    return orbit_camera(orbit_view(decoder.extent_mu(), s), p.width, p.height, &c);
  };
  const uint64_t record = view.record_bytes;
  Camera c;
  if (!camera_at(base.yaw, c) || cut.update(c, p) != CutStatus::kOk) return cli::fail("cut: the view is out of range");
  const uint64_t cold_nodes = cut.sent_count(), cold_culled = cut.culled_count(), cold_bytes = cold_nodes * node_entry_bytes(record);
  double sent = 0, entered = 0, left = 0, visited = 0, evaluated = 0, change_bytes = 0, resend_bytes = 0, derived = 0;
  for (unsigned long long k = 1; k <= steps; ++k) {
    if (!camera_at(base.yaw + 360.0 * static_cast<double>(k) / static_cast<double>(steps), c) ||
        cut.update(c, p) != CutStatus::kOk)
      return cli::fail("cut: an orbit camera is out of range");
    sent += cut.sent_count();
    entered += cut.entered_count();
    left += cut.left_count();
    visited += cut.visited();
    evaluated += cut.evaluated();
    derived += incremental && !cut.last_was_incremental();
    change_bytes += static_cast<double>(cut.entered_count() * node_entry_bytes(record) + cut.left_count() * 4);
    resend_bytes += static_cast<double>(cut.sent_count() * node_entry_bytes(record));
  }
  const double n = static_cast<double>(steps);
  if (json) {
    cli::Json j;
    j.str("model", files[0])
        .integer("width", p.width)
        .integer("height", p.height)
        .integer("record_bytes", static_cast<long long>(record))
        .integer("cold_sent", static_cast<long long>(cold_nodes))
        .integer("cold_culled", static_cast<long long>(cold_culled))
        .integer("cold_bytes", static_cast<long long>(cold_bytes))
        .integer("orbit_steps", static_cast<long long>(steps))
        .num("sent_per_step", sent / n)
        .num("entered_per_step", entered / n)
        .num("left_per_step", left / n)
        .num("visited_per_step", visited / n)
        .num("evaluated_per_step", evaluated / n)
        .integer("derived_from_the_root", static_cast<long long>(derived))
        .num("change_bytes_per_step", change_bytes / n)
        .num("resend_bytes_per_step", resend_bytes / n)
        .num("change_share", resend_bytes > 0 ? change_bytes / resend_bytes : 0);
    std::printf("%s\n", j.done().c_str());
    return 0;
  }
  std::printf("%s, %ux%u: cold start %s nodes sent, %s culled, %s bytes\n", files[0].c_str(), p.width, p.height,
              cli::with_commas(cold_nodes).c_str(), cli::with_commas(cold_culled).c_str(), cli::with_commas(cold_bytes).c_str());
  std::printf("orbit of %llu steps, per step: %.0f sent, %.1f entered, %.1f left, %.0f visited, %.0f evaluated; %.0f "
              "bytes of change against %.0f resending the cut (%.1f %%)\n",
              steps, sent / n, entered / n, left / n, visited / n, evaluated / n, change_bytes / n, resend_bytes / n,
              resend_bytes > 0 ? 100 * change_bytes / resend_bytes : 0.0);
  if (incremental)
    std::printf("incremental: %.0f of %llu steps derived from the root\n", derived, steps);
  return 0;
}

}  // namespace stipple
