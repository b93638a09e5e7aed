/// @file picture.h
/// @brief A shaded picture of a part, so a user can look at a result without a mesh viewer: an
/// orthographic view (isometric by default) fitted to the part, rendered by a small z-buffer
/// rasteriser with smooth normals and two lights, written as PNG with libpng.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/surface/mesh.h"

namespace dexelmill {

/// @brief An 8-bit RGB image, rows top to bottom.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> rgb;  ///< 3 * width * height bytes

    const std::uint8_t* pixel(int x, int y) const { return &rgb[3 * (std::size_t(y) * width + x)]; }
};

/// @brief How to render a picture.
struct PictureOptions {
    int width = 1200;
    int height = 900;
    /// Samples per pixel along each axis (anti-aliasing), 1 to 4.
    int supersample = 2;
    /// Direction from the part towards the viewer; the default is the isometric view from the
    /// front-right-top (x right, y away, z up).
    Vec3 viewDirection{1.0, -1.0, 1.0};
    /// Fraction of the picture left as margin around the part on each side.
    double margin = 0.05;
};

/// @brief Renders the mesh: orthographic, fitted to its projected bounds, z-buffered, with
/// per-pixel interpolated vertex normals, a key light, a fill light and a specular highlight so
/// that machined surfaces and scallops show. The background is a light gradient.
/// @throw Error if the sizes are out of range or the view direction is zero.
Image renderPicture(const Mesh& mesh, const PictureOptions& options = {});

/// @brief Writes an image as an 8-bit RGB PNG (through writeFileAtomically).
/// @throw Error on any failure.
void writePng(const std::string& path, const Image& image);

/// @brief renderPicture then writePng.
void writePicture(const std::string& path, const Mesh& mesh, const PictureOptions& options = {});

}  // namespace dexelmill
