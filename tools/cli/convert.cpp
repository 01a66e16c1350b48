// stipple convert — a .spg written again as another version: 2 (records
// plain, what servers map) or 3 (records coded, a third smaller).
#include <cstdio>
#include <string>
#include <vector>

#include "core/spg_format.h"
#include "platform/file_io.h"
#include "platform/progress.h"
#include "tools/cli/cli.h"
#include "tools/embedded/embedded.h"
#include "tools/embedded/model_file.h"
#include "tools/encoder/coded_file.h"

namespace stipple {
namespace {

const char kConvertHelp[] =
    "usage: stipple convert MODEL.spg -o OUT.spg --format-version V\n"
    "\n"
    "Writes the model again as .spg version V (docs/format.md):\n"
    "  3  the records entropy-coded, each child against its parent: about a\n"
    "     third smaller; every reader expands it in memory when it opens it\n"
    "  2  the records as they are: what servers and viewers map without\n"
    "     reading the whole file (a model larger than memory wants it)\n"
    "The model is the same either way: version 3 expands to the very bytes of\n"
    "its version 2 file. A cut table beside the input serves the output too\n"
    "(it is the same model); stipple cut-table OUT.spg writes one.\n";

}  // namespace

int cmd_convert(int argc, char** argv) {
  cli::Args args(argc, argv, 2);
  if (args.flag("--help") || args.flag("-h")) {
    std::fputs(kConvertHelp, stdout);
    return 0;
  }
  std::string output, version_text, error;
  if (!args.value("-o", output)) args.value("--output", output);
  const bool has_version = args.value("--format-version", version_text);
  const std::vector<std::string> files = args.positionals();
  if (args.bad()) return cli::fail("convert: " + args.error());
  if (!args.unknown_option().empty()) return cli::fail("convert: " + args.unknown_option_message());
  if (files.size() != 1) return cli::fail("convert: expected one .spg file (see stipple convert --help)");
  if (output.empty()) return cli::fail("convert: -o OUT.spg is required");
  if (!has_version || (version_text != "2" && version_text != "3"))
    return cli::fail("convert: --format-version: expected 2 or 3" +
                     (has_version ? ", got '" + version_text + "'" : std::string(" (it is required)")));
  if (!cli::check_output_name(output, ".spg", "a .spg model", error)) return cli::fail("convert: " + error);
  if (cli::output_is_input(files[0], output, error)) return cli::fail("convert: " + error);
  std::vector<uint8_t> file;
  if (!read_spg_file(files[0], file, error)) return cli::fail(error);
  SpgView view;
  if (const SpgResult r = spg_parse(file.data(), file.size(), &view); !r.ok())
    return cli::fail(spg_error_message(files[0], r, file.data(), file.size()));
  if (view.header.version != kSpgVersion)
    return cli::fail(files[0] + ": version " + std::to_string(view.header.version) +
                     " (float32 class tables): re-encode it (stipple encode SCAN -o MODEL.spg) to convert it");
  std::vector<uint8_t> coded;
  CodedFileReport report;
  if (version_text == "3") {
    ProgressBar progress("convert");  // on a terminal only
    if (!write_coded_spg(file.data(), file.size(), coded, report, error,
                         [&](double done) { progress.update(done, "coding records"); }))
      return cli::fail(files[0] + ": " + error);
  }
  const std::vector<uint8_t>& out = version_text == "3" ? coded : file;
  if (!write_file_atomic(output, out, error)) return cli::fail("convert: " + error);
  std::printf("%s: version %s, %s bytes (%s bytes as version 2)\n", output.c_str(), version_text.c_str(),
              cli::with_commas(out.size()).c_str(), cli::with_commas(file.size()).c_str());
  if (version_text == "3") {
    const int widths = view.header.layout.bits[0] + view.header.layout.bits[1] + view.header.layout.bits[2];
    std::printf("  the mean's bits a node by depth (version 2: %d each):", widths);
    for (size_t d = 0; d < report.mean_bits_by_depth.size(); ++d)
      std::printf("%s %zu: %.1f", d % 8 == 0 ? "\n   " : "", d, report.mean_bits_by_depth[d]);
    std::printf("\n");
  }
  return 0;
}

}  // namespace stipple
