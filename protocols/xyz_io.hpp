#pragma once
// Plain-text pair exchange (docs/benchmark-format.md): DIR/NNNN_src.xyz, NNNN_tgt.xyz (one
// "x y z" per line) and NNNN_gt.txt (4 x 4 row-major, maps source into target); PLY export.
#include <string>

#include "core/point_cloud.hpp"
#include "protocols/pair.hpp"

namespace regbench {

/// Reads one "x y z" per line; blank lines and lines starting with '#' are skipped. Throws
/// std::runtime_error "path:line: ..." on a malformed line, a non-finite value or no points.
PointCloud ReadXyz(const std::string& path);
/// Reads a 4 x 4 row-major rigid transform (4 lines of 4 numbers). Throws "path:line: ..."
/// on a malformed line, a last row other than 0 0 0 1 or a non-rotation block.
Transform ReadTransformTxt(const std::string& path);

/// File stem of pair k: at least four digits, zero padded ("0007").
std::string PairStem(std::size_t k);

/// Writes every pair as DIR/NNNN_src.xyz, NNNN_tgt.xyz, NNNN_gt.txt (creates DIR). Values are
/// written with 17 significant digits, so a re-import gives the same doubles.
void ExportXyz(const PairSet& set, const std::string& dir);
/// Writes DIR/NNNN_src.ply, NNNN_tgt.ply (ASCII PLY, double x y z) and NNNN_gt.txt.
void ExportPly(const PairSet& set, const std::string& dir);

/// ASCII PLY of two clouds in one file, to look at an alignment in any viewer: the points of
/// `source` (e.g. moved by an estimate) coloured orange (255 128 0), then `target`'s blue
/// (0 102 255); x y z as doubles with 17 significant digits, red green blue as uchar.
std::string TwoCloudPlyText(const PointCloud& source, const PointCloud& target);

/// Reads DIR/NNNN_{src,tgt}.xyz + NNNN_gt.txt for NNNN = 0000, 0001, ... (contiguous; every
/// pair needs all three files) and labels overlap by radius `eta`. Shape names are the stems.
/// Throws std::runtime_error naming the file (and line) at the first problem.
PairSet ImportXyzDir(const std::string& dir, double eta);

}  // namespace regbench
