/// @file mesh_io.h
/// @brief Triangle mesh files: OBJ, binary STL and binary PLY out; STL (binary or ASCII) in.
/// Every writer goes through writeFileAtomically: given an OutputBatch, it stages its file there.
#pragma once

#include <string>
#include <vector>

#include "dexelmill/io/atomic_file.h"
#include "dexelmill/io/colour.h"
#include "dexelmill/surface/mesh.h"

namespace dexelmill {

/// @brief Writes a Wavefront OBJ: "v x y z" lines (shortest round-trip decimal), then
/// "f a b c" with 1-based indices.
/// @throw Error on any I/O failure (the target is then untouched).
void writeObj(const std::string& path, const Mesh& mesh, OutputBatch* batch = nullptr);

/// @brief Writes a binary STL: 80-byte header, triangle count, per triangle the unit normal,
/// three vertices (32-bit little-endian floats) and a zero attribute word.
/// @throw Error on any I/O failure, or more than 2^32 - 1 triangles.
void writeStl(const std::string& path, const Mesh& mesh, OutputBatch* batch = nullptr);

/// @brief What a PLY may carry per vertex besides its position; each list is empty or holds one
/// entry per vertex.
struct PlyVertexData {
    std::vector<Rgb> colours;  ///< written as uchar red, green, blue
    std::string scalarName;    ///< the name of the scalar property, e.g. "deviation_mm"
    std::vector<double> scalar;  ///< written as float
};

/// @brief Writes a binary little-endian PLY: float x, y, z per vertex (then the colours and the
/// scalar of `data`, when given); uchar count and int indices per face.
/// @throw Error on any I/O failure, or lists in `data` whose length is not the vertex count.
void writePly(const std::string& path, const Mesh& mesh, const PlyVertexData& data = {},
              OutputBatch* batch = nullptr);

/// @brief Reads an STL file, binary or ASCII. Binary when the size is exactly 84 + 50 n bytes,
/// n being the count at byte 80 (many binary files start with "solid" too); ASCII otherwise.
/// Vertices with identical coordinates are merged, so a closed STL gives a closed mesh.
/// @throw ParseError with file, line and column on malformed ASCII; Error if the file cannot be
/// read or holds no triangle.
Mesh readStl(const std::string& path);

}  // namespace dexelmill
