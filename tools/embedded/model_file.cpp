// stipple — a .spg model as every program reads it. See model_file.h.
#include "tools/embedded/model_file.h"

#include <sys/stat.h>

#include <cstring>

#include "core/cut_table.h"
#include "core/spg_coded.h"
#include "tools/embedded/embedded.h"

namespace stipple {

bool spg_is_coded(const uint8_t* data, size_t size) {
  return size >= spg_offset::kVersion + 2 && std::memcmp(data, kSpgMagic, 4) == 0 &&
         load_u16le(data + spg_offset::kVersion) == kSpgCodedVersion;
}

bool expand_coded_spg(const uint8_t* data, size_t size, const std::string& name, std::vector<uint8_t>& image,
                      std::string& error) {
  SpgView view;
  SpgCodedParts parts;
  if (const SpgResult r = spg_parse_coded(data, size, &view, &parts); !r.ok())
    return error = spg_error_message(name, r, data, size), false;
  image.resize(spg_expanded_bytes(view, parts));
  std::vector<uint8_t> points(view.header.node_count);
  if (const SpgResult r = spg_expand(data, view, parts, image.data(), points.data()); !r.ok()) {
    if (r.error == SpgError::kBadCoded) return error = spg_error_message(name, r, size), false;
    return error = name + ": its records, decoded (version 3), do not form a model: " +
                   spg_error_message("byte", r, image.size()) + " of the expanded file",
           false;
  }
  return true;
}

bool expand_coded_spg(std::vector<uint8_t>& file, const std::string& name, std::string& error) {
  if (!spg_is_coded(file.data(), file.size())) return true;
  std::vector<uint8_t> image;
  if (!expand_coded_spg(file.data(), file.size(), name, image, error)) return false;
  file.swap(image);
  return true;
}

bool read_spg_file(const std::string& path, std::vector<uint8_t>& out, std::string& error) {
  return read_file(path, out, error) && expand_coded_spg(out, path, error);
}

std::string cut_table_path(const std::string& model_path) { return model_path + ".cut"; }

bool ModelFile::open(const std::string& path, const ConeRule& cones, std::string& error) {
  name_ = path;
  cones_ = cones;
  if (!mapped_.open(path, error)) return false;
  data_ = mapped_.data();
  size_ = mapped_.size();
  if (spg_is_coded(data_, size_)) {  // version 3: expanded once, held in memory
    if (!expand_coded_spg(data_, size_, path, owned_, error)) return false;
    mapped_.close();
    expanded_ = true;
    data_ = owned_.data();
    size_ = owned_.size();
  }
  if (!validate(error)) return false;
  const std::string table_path = cut_table_path(path);
  struct stat st {};
  if (::stat(table_path.c_str(), &st) != 0) {
    table_note_ = "no cut table (" + table_path + "; stipple cut-table writes one): the cut's bounds are built in memory";
    return build_bounds(error);
  }
  std::string why;
  if (table_.open(table_path, why)) {
    const CutTableResult r =
        cut_table_attach(table_.data(), table_.size(), view_, model_tag(data_, size_), cones, &bounds_);
    if (r.ok()) {
      table_note_ = "cut table " + table_path + " mapped";
      return true;
    }
    why = table_path + ": " + cut_table_error_text(r.error);
    if (r.error == CutTableError::kBadNode) why += " (node " + std::to_string(r.node) + ", " + r.field + ")";
  }
  table_.close();
  table_refused_ = true;
  table_note_ = why + "; the cut's bounds are built in memory";
  return build_bounds(error);
}

bool ModelFile::adopt(std::vector<uint8_t> file, const std::string& name, const ConeRule& cones, std::string& error) {
  owned_ = std::move(file);
  expanded_ = spg_is_coded(owned_.data(), owned_.size());
  if (!expand_coded_spg(owned_, name, error)) return false;
  name_ = name;
  cones_ = cones;
  data_ = owned_.data();
  size_ = owned_.size();
  return validate(error) && build_bounds(error);
}

bool ModelFile::validate(std::string& error) {
  const SpgResult r = spg_parse(data_, size_, &view_);
  if (!r.ok()) return error = spg_error_message(name_, r, data_, size_), false;
  decoder_storage_.assign(node_decoder_bytes(view_.header) / 4 + 1, 0);
  if (decoder_.init(view_, decoder_storage_.data(), decoder_storage_.size() * 4) != DecodeStatus::kOk)
    return error = name_ + ": the angle fields are wider than the decoder supports", false;
  return true;
}

bool ModelFile::build_bounds(std::string& error) {
  bounds_storage_.assign(CutBounds::bytes(view_.header) / 8 + 1, 0);
  if (bounds_.init(view_, decoder_, bounds_storage_.data(), bounds_storage_.size() * 8, cones_) != CutStatus::kOk)
    return error = name_ + ": the cut's bounds could not be built", false;
  return true;
}

bool ModelFile::write_table(const std::string& path, std::string& error) const {
  uint8_t header[kCutTableHeaderBytes];
  cut_table_header(model_tag(data_, size_), cones_, bounds_, header);
  AtomicFileWriter out;
  if (!out.open(path, error)) return false;
  const size_t nodes = cut_table_bytes(view_.header.node_count) - kCutTableHeaderBytes;
  if (!out.write(header, sizeof header) || !out.write(bounds_.table(), nodes)) return error = out.failure(), false;
  return out.commit(error);
}

bool make_cut_table(const std::string& path, const ConeRule& cones, std::string& error, bool* written) {
  ModelFile model;
  if (!model.open(path, cones, error)) return false;
  if (written) *written = !model.table_mapped();
  return model.table_mapped() || model.write_table(cut_table_path(path), error);
}

}  // namespace stipple
