// stipple host — the last step of the encoder in partitions
// (tools/encoder/partition.h): the top nodes from their children's moments,
// the sigma classes from a sample of the nodes, and the .spg written
// breadth-first, a piece at a time.
//
// Upper nodes: positions and colours exactly (Moments: counts, means and
// centred sums of outer products, Chan et al.'s pairwise update). Normals: the mean from
// the children's summed normals; the spread from the children's, each turned
// into the parent's tangent plane and offset by the log map of its mean —
// the second moment of the mixture — then scaled so its trace is the bound
// the triangle inequality gives (sum w (|a| + s)^2, a the child's offset, s
// its RMS angle). The cut's back-face cones take sigma_n as an angle, so an
// upper node's spread is never understated (docs/encoder.md "Partitions").
//
// Classes: the tuples of every node when there are at most 2^21 nodes (so a
// scan of one partition gets the classes encode_cloud always gave), else of
// a hashed sample of 2^21; then each node's class while its record is
// written.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "tools/encoder/partition.h"

namespace stipple {

// Receives the file's bytes in order; false stops the merge (its error then
// says why: "write failed ...").
using ByteSink = std::function<bool(const uint8_t* data, size_t size, std::string& error)>;

class AtomicFileWriter;
// The sink into a file being written (platform/file_io.h), its failure the
// file's ("<path>: write failed: No space left on device").
ByteSink sink_into(AtomicFileWriter& file);

bool merge_parts(const PartitionPlan& plan, std::vector<std::unique_ptr<PartNodes>>& parts, int threads,
                 const ByteSink& sink, EncodeReport& report, std::string& error, ProgressBar* progress = nullptr);

// The upper nodes' normal spread from their two (or more) children's, as above.
NormalSpread combine_normal_spreads(const NodeStats* children, const double* counts, size_t n, const Vec3& normal_sum,
                                    const Vec3& fallback_z);

}  // namespace stipple
