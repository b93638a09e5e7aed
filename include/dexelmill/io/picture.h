/// @file picture.h
/// @brief A shaded picture of a part, so a user can look at a result without a mesh viewer: an
/// orthographic view (isometric by default) fitted to the part, rendered by a small z-buffer
/// rasteriser with smooth normals and two lights, written as PNG with libpng.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dexelmill/geometry/types.h"
#include "dexelmill/io/atomic_file.h"
#include "dexelmill/io/colour.h"
#include "dexelmill/surface/mesh.h"

namespace dexelmill {

/// @brief An 8-bit RGB image, rows top to bottom.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> rgb;  ///< 3 * width * height bytes

    const std::uint8_t* pixel(int x, int y) const { return &rgb[3 * (std::size_t(y) * width + x)]; }
};

/// @brief A colour bar beside the part that says what its colours mean.
struct PictureLegend {
    std::string title;     ///< above the bar, e.g. "deviation (mm)"
    std::vector<Rgb> bar;  ///< the bar's colours, bottom to top, spread evenly over its height
    /// A text beside the bar at a height `at` (0 bottom, 1 top), with a tick mark or without.
    struct Label {
        double at = 0.0;
        std::string text;
        bool tick = true;
    };
    std::vector<Label> labels;
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
    /// The colour of every vertex, interpolated across the triangles; null paints the part light
    /// steel. Not owned.
    const std::vector<Rgb>* vertexColours = nullptr;
    /// A legend drawn at the right, the part fitted into the rest; null draws none. Not owned.
    const PictureLegend* legend = nullptr;
};

/// @brief Renders the mesh: orthographic, fitted to its projected bounds, z-buffered, with
/// per-pixel interpolated vertex normals, a key light, a fill light and a specular highlight so
/// that machined surfaces and scallops show. The background is a light gradient.
/// @throw Error if the sizes are out of range, the view direction is zero, or there are vertex
/// colours for another number of vertices.
Image renderPicture(const Mesh& mesh, const PictureOptions& options = {});

/// @brief Draws text (stb_easy_font's glyphs, about 7 pixels tall at scale 1, each glyph pixel
/// `scale` pixels wide and tall) with its top-left corner at (x, y); what falls outside the image
/// is clipped. Line breaks start a new line.
void drawText(Image& image, int x, int y, const std::string& text, const Rgb& colour, int scale = 1);

/// @brief The width in pixels drawText gives the text's widest line.
int textWidth(const std::string& text, int scale = 1);

/// @brief Writes an image as an 8-bit RGB PNG (through writeFileAtomically; staged in `batch`
/// when given).
/// @throw Error on any failure.
void writePng(const std::string& path, const Image& image, OutputBatch* batch = nullptr);

/// @brief renderPicture then writePng.
void writePicture(const std::string& path, const Mesh& mesh, const PictureOptions& options = {},
                  OutputBatch* batch = nullptr);

}  // namespace dexelmill
