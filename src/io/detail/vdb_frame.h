/// @file vdb_frame.h
/// @brief Checks the lengths and offsets that frame an OpenVDB file (its header, metadata and grid
/// descriptors, and each grid's own metadata) against the file's size, before OpenVDB reads it:
/// OpenVDB's reader allocates and fills a name, string or metadata value of whatever length the
/// file gives (up to 4 GB) before the file's end refuses it.
#pragma once

#include <cstdint>
#include <istream>
#include <optional>
#include <string>

namespace dexelmill::detail {

/// @brief A length or offset that frames an OpenVDB file and that the file cannot hold.
struct VdbFramingProblem {
    std::string what;  ///< a phrase naming the field, its value and its byte offset
    bool cutShort;     ///< a grid's end offset lies past the file's end: the file stops short (or that
                       ///< offset is damaged)
};

/// @brief The first length or offset in the framing of the OpenVDB file `in` (of `size` bytes,
/// read from its start) that the file cannot hold; none where every one fits.
///
/// Judged: each name's, string's and metadata value's length against the bytes left; a value of
/// a fixed-size metadata type against that size; the leaf count and Blosc sizes inside the
/// "__delayedload" value OpenVDB writes with a grid (it sizes arrays by them); and the grid, block
/// and end offsets of each descriptor, in order from the descriptor's end to the file's end. Only
/// in the format versions whose layout was verified, 222 to 224: another magic number or version,
/// the file ending inside a fixed-size field or a stream that fails give none, and are left to
/// OpenVDB's reader. The grids' trees are not looked at. Where the file holds no grid offsets (as
/// written to a pipe), only the first grid's metadata is reached: the next descriptor follows that
/// grid's tree.
std::optional<VdbFramingProblem> vdbFramingProblem(std::istream& in, std::uint64_t size);

}  // namespace dexelmill::detail
