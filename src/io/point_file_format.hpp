#pragma once
// Private: the header parsers and point decoder shared by the PCD/PLY map readers (map_io.hpp) and
// the scan files of a drive folder (FolderDriveReader). Parse-from-memory, so the fuzz target
// fuzz/fuzz_pcd.cpp runs exactly the code the readers run.
//
// PCD v0.7: FIELDS, SIZE, TYPE, COUNT (optional, default 1), WIDTH, HEIGHT, VIEWPOINT, POINTS, DATA
// ascii | binary (binary_compressed: kUnimplemented). PLY: format ascii | binary_little_endian |
// binary_big_endian, the first element must be `vertex` (scalar properties only); later elements
// (faces) are ignored. Bytes after the declared points are ignored (PCL pads some files with
// zeros); fewer bytes or lines than declared is kDataLoss naming the file and the counts.
//
// Thread safety: pure functions; safe from any thread.

#include <string>
#include <string_view>
#include <vector>

#include "slam_mms/core/status.hpp"

namespace slam_mms::io_internal {

/// A scalar type of PLY or PCD, by kind and byte size.
struct ScalarType {
  char kind = 'F';  ///< 'F' float, 'I' signed, 'U' unsigned.
  int size = 4;     ///< Bytes: F 4 or 8; I/U 1, 2, 4 or 8.
};

/// The value at `p` as double (float32 and integers up to 2^53 exactly).
double ReadTyped(const char* p, ScalarType type, bool little_endian);

enum class PointEncoding { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

/// One value of a point record. A PCD field with COUNT n gives n columns with the same name and
/// element 0..n-1.
struct PointColumn {
  std::string name;
  int element = 0;
  int count = 1;
  ScalarType type;
  size_t offset = 0;  ///< Byte offset within a binary record.
};

/// What a PCD or PLY header declares.
struct PointFileLayout {
  const char* format = "PCD";    ///< "PCD" or "PLY", for messages.
  const char* noun = "point";    ///< "point" (PCD) or "vertex" (PLY), for messages.
  const char* nouns = "points";  ///< Plural.
  PointEncoding encoding = PointEncoding::kAscii;
  std::vector<PointColumn> columns;
  size_t record_size = 0;  ///< Bytes per binary record.
  size_t num_points = 0;
  size_t data_offset = 0;  ///< First byte after the header.
  int header_lines = 0;    ///< Lines of the header (ascii data starts on line header_lines + 1).

  /// Index of the column of a COUNT-1 field named `name`; -1 when absent.
  int ColumnIndex(std::string_view name) const;
};

/// Parses a PCD header. Errors (kDataLoss; kUnimplemented for binary_compressed) name
/// "<file>:<line>" and the key ("FIELDS has 4 entries but SIZE has 3").
StatusOr<PointFileLayout> ParsePcdHeader(std::string_view bytes, const std::string& file);

/// Parses a PLY header (see the file comment). A PLY without a `vertex` element is kDataLoss; a
/// `vertex` element after another element or with list properties is kUnimplemented.
StatusOr<PointFileLayout> ParsePlyHeader(std::string_view bytes, const std::string& file);

/// Decodes the columns `wanted` (indices into layout.columns; -1 = absent, filled with 0) of every
/// point into `values` (num_points rows of wanted.size() floats). Ascii values are parsed with
/// strtod ("nan" accepted) and rounded to float, binary float32 values are copied exactly.
/// kDataLoss when the data holds fewer points than declared ("<file>: PCD binary data has 100
/// bytes, expected at least 160 for 10 points of 16 bytes: only 6 of 10 points") or an ascii line
/// has the wrong number of values or a non-number ("<file>:<line>: point has 3 values, expected
/// 4").
Status DecodePointColumns(std::string_view bytes, const PointFileLayout& layout,
                          const std::string& file, const std::vector<int>& wanted,
                          std::vector<float>* values);

}  // namespace slam_mms::io_internal
