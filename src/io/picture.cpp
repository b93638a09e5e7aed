#include "dexelmill/io/picture.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include <png.h>
#include <stb/stb_easy_font.h>

#include "dexelmill/error.h"
#include "dexelmill/io/atomic_file.h"

namespace dexelmill {

namespace {

/// The view: orthonormal right / up / towards-viewer axes.
struct Camera {
    Vec3 right, up, back;
    double scale = 1.0;  // pixels per mm
    double x0 = 0.0, y0 = 0.0;

    Camera(Vec3 viewDirection) {
        back = glm::normalize(viewDirection);
        // Keep +z up on the screen unless looking straight along z.
        const Vec3 worldUp = std::abs(back.z) > 0.999 ? Vec3(0.0, 1.0, 0.0) : Vec3(0.0, 0.0, 1.0);
        right = glm::normalize(glm::cross(worldUp, back));
        up = glm::cross(back, right);
    }
    /// Screen position (pixels, y down) and depth (larger is nearer the viewer).
    Vec3 project(const Vec3& p) const {
        return {(glm::dot(p, right) - x0) * scale, (y0 - glm::dot(p, up)) * scale, glm::dot(p, back)};
    }
};

std::vector<Vec3> vertexNormals(const Mesh& mesh) {
    std::vector<Vec3> n(mesh.vertices.size(), Vec3(0.0));
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Vec3 a = mesh.areaVector(t);  // area-weighted
        for (std::uint32_t i : mesh.triangles[t]) n[i] += a;
    }
    for (Vec3& v : n) {
        const double len = glm::length(v);
        v = len > 0.0 ? v / len : Vec3(0.0, 0.0, 1.0);
    }
    return n;
}

double clamp01(double v) { return std::min(1.0, std::max(0.0, v)); }

/// An 8-bit sRGB value in linear light (the renderer shades in linear light, then applies the
/// display gamma).
double linear(std::uint8_t c) { return std::pow(c / 255.0, 2.2); }

/// How a legend sits in the picture: its text scale and parts (pixels).
struct LegendLayout {
    int scale = 1;  ///< font pixels per glyph pixel
    int pad = 0, barWidth = 0, gap = 0, width = 0;
};

/// stb_easy_font's capital height, in glyph pixels.
constexpr int kTextHeight = 7;

LegendLayout layoutLegend(const PictureLegend& legend, int height) {
    LegendLayout l;
    l.scale = std::max(1, height / 450);
    l.pad = 6 * l.scale;
    l.barWidth = 8 * l.scale;
    l.gap = 3 * l.scale;
    int longest = 0;
    for (const PictureLegend::Label& label : legend.labels) longest = std::max(longest, textWidth(label.text, l.scale));
    l.width = std::max(l.pad + l.barWidth + l.gap + l.scale + longest + l.pad, 2 * l.pad + textWidth(legend.title, l.scale));
    return l;
}

void fill(Image& img, int x0, int y0, int x1, int y1, const Rgb& c) {
    for (int y = std::max(0, y0); y < std::min(img.height, y1); ++y)
        for (int x = std::max(0, x0); x < std::min(img.width, x1); ++x)
            std::copy(c.begin(), c.end(), &img.rgb[3 * (std::size_t(y) * img.width + x)]);
}

/// Draws the legend in the rightmost `layout.width` columns: the title, the bar (60 % of the
/// height, centred) with a dark frame, and the labels beside it.
void drawLegend(Image& img, const PictureLegend& legend, const LegendLayout& l) {
    const Rgb ink{40, 40, 40};
    const int left = img.width - l.width + l.pad;
    const int barTop = int(0.2 * img.height), barBottom = int(0.8 * img.height);
    const int textHeight = kTextHeight * l.scale;
    drawText(img, left, barTop - textHeight - 2 * l.pad, legend.title, ink, l.scale);
    fill(img, left - 1, barTop - 1, left + l.barWidth + 1, barBottom + 1, ink);
    const int span = barBottom - barTop;
    for (int y = barTop; y < barBottom && !legend.bar.empty(); ++y) {
        // Row y shows the colour at height (barBottom - y - 0.5) / span from the bottom.
        const double at = (barBottom - y - 0.5) / span;
        const std::size_t k = std::min(legend.bar.size() - 1, std::size_t(at * double(legend.bar.size())));
        fill(img, left, y, left + l.barWidth, y + 1, legend.bar[k]);
    }
    for (const PictureLegend::Label& label : legend.labels) {
        const int y = barBottom - int(std::lround(clamp01(label.at) * span));
        if (label.tick) fill(img, left + l.barWidth, y - l.scale / 2, left + l.barWidth + l.gap, y - l.scale / 2 + l.scale, ink);
        drawText(img, left + l.barWidth + l.gap + l.scale, y - textHeight / 2, label.text, ink, l.scale);
    }
}

}  // namespace

Image renderPicture(const Mesh& mesh, const PictureOptions& options) {
    if (options.width < 1 || options.height < 1 || options.width > 16384 || options.height > 16384)
        throw Error("picture size must be between 1 and 16384 pixels");
    if (options.supersample < 1 || options.supersample > 4)
        throw Error("picture supersampling must be 1 to 4");
    if (!(glm::length(options.viewDirection) > 0.0)) throw Error("picture view direction is zero");
    const std::vector<Rgb>* colours = options.vertexColours;
    if (colours && colours->size() != mesh.vertices.size())
        throw Error("picture: colours for " + std::to_string(colours->size()) + " vertices, the mesh has " +
                    std::to_string(mesh.vertices.size()));
    LegendLayout legend;
    if (options.legend) {
        legend = layoutLegend(*options.legend, options.height);
        if (legend.width * 3 > options.width) throw Error("picture too narrow for its legend");
    }

    const int ss = options.supersample;
    const int W = options.width * ss, H = options.height * ss;
    Camera cam(options.viewDirection);

    // Fit the projected bounds into the picture, keeping the aspect ratio.
    double xmin = std::numeric_limits<double>::infinity(), xmax = -xmin, ymin = xmin, ymax = -xmin;
    for (const Vec3& v : mesh.vertices) {
        const double x = glm::dot(v, cam.right), y = glm::dot(v, cam.up);
        xmin = std::min(xmin, x);
        xmax = std::max(xmax, x);
        ymin = std::min(ymin, y);
        ymax = std::max(ymax, y);
    }
    if (mesh.vertices.empty()) xmin = xmax = ymin = ymax = 0.0;
    const double usable = 1.0 - 2.0 * options.margin;
    // The part fits beside the legend.
    const int partW = W - legend.width * ss;
    const double sx = (xmax - xmin) > 0 ? usable * partW / (xmax - xmin) : 1.0;
    const double sy = (ymax - ymin) > 0 ? usable * H / (ymax - ymin) : 1.0;
    cam.scale = std::min(sx, sy);
    cam.x0 = 0.5 * (xmin + xmax) - 0.5 * partW / cam.scale;
    cam.y0 = 0.5 * (ymin + ymax) + 0.5 * H / cam.scale;

    // Lights in view space terms: key from upper left, fill from the right, both towards the
    // viewer; Blinn-Phong specular on the key light.
    const Vec3 key = glm::normalize(-0.6 * cam.right + 0.6 * cam.up + 0.55 * cam.back);
    const Vec3 fill = glm::normalize(0.7 * cam.right - 0.2 * cam.up + 0.7 * cam.back);
    const Vec3 halfKey = glm::normalize(key + cam.back);
    const Vec3 steel(0.62, 0.66, 0.72);
    std::vector<Vec3> vertexColour;
    if (colours)
        for (const Rgb& c : *colours) vertexColour.emplace_back(linear(c[0]), linear(c[1]), linear(c[2]));

    std::vector<float> depth(std::size_t(W) * H, -std::numeric_limits<float>::infinity());
    std::vector<float> color(std::size_t(W) * H * 3);
    for (int y = 0; y < H; ++y) {
        const double g = 0.97 - 0.17 * double(y) / H;  // background gradient
        for (int x = 0; x < W; ++x) {
            float* c = &color[3 * (std::size_t(y) * W + x)];
            c[0] = float(g * 0.93);
            c[1] = float(g * 0.95);
            c[2] = float(g);
        }
    }

    const std::vector<Vec3> normals = vertexNormals(mesh);
    std::vector<Vec3> screen(mesh.vertices.size());
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) screen[i] = cam.project(mesh.vertices[i]);

    for (const Mesh::Triangle& t : mesh.triangles) {
        const Vec3 &a = screen[t[0]], &b = screen[t[1]], &c = screen[t[2]];
        // Twice the signed screen area; y points down, so front faces have negative area.
        const double area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if (!(area < 0.0)) continue;  // back face or edge-on
        const int x0 = std::max(0, int(std::floor(std::min({a.x, b.x, c.x}))));
        const int x1 = std::min(W - 1, int(std::ceil(std::max({a.x, b.x, c.x}))));
        const int y0 = std::max(0, int(std::floor(std::min({a.y, b.y, c.y}))));
        const int y1 = std::min(H - 1, int(std::ceil(std::max({a.y, b.y, c.y}))));
        for (int py = y0; py <= y1; ++py) {
            for (int px = x0; px <= x1; ++px) {
                const double qx = px + 0.5, qy = py + 0.5;
                // Barycentric weights (all <= 0 inside for this orientation).
                const double w0 = ((c.x - b.x) * (qy - b.y) - (c.y - b.y) * (qx - b.x)) / area;
                const double w1 = ((a.x - c.x) * (qy - c.y) - (a.y - c.y) * (qx - c.x)) / area;
                const double w2 = 1.0 - w0 - w1;
                if (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) continue;
                const float z = float(w0 * a.z + w1 * b.z + w2 * c.z);
                const std::size_t pix = std::size_t(py) * W + px;
                if (z <= depth[pix]) continue;
                depth[pix] = z;
                Vec3 n = w0 * normals[t[0]] + w1 * normals[t[1]] + w2 * normals[t[2]];
                const double len = glm::length(n);
                n = len > 0.0 ? n / len : cam.back;
                const double diffuse =
                    0.8 * clamp01(glm::dot(n, key)) + 0.15 * clamp01(glm::dot(n, fill));
                const double spec = std::pow(clamp01(glm::dot(n, halfKey)), 40.0) * 0.35;
                const Vec3 base = colours ? w0 * vertexColour[t[0]] + w1 * vertexColour[t[1]] + w2 * vertexColour[t[2]]
                                          : steel;
                const Vec3 col = base * (0.18 + 0.85 * diffuse) + Vec3(spec);
                float* out = &color[3 * pix];
                for (int k = 0; k < 3; ++k) out[k] = float(clamp01(col[k]));
            }
        }
    }

    Image img;
    img.width = options.width;
    img.height = options.height;
    img.rgb.resize(std::size_t(img.width) * img.height * 3);
    const double inv = 1.0 / (ss * ss);
    for (int y = 0; y < img.height; ++y) {
        for (int x = 0; x < img.width; ++x) {
            for (int k = 0; k < 3; ++k) {
                double sum = 0.0;
                for (int j = 0; j < ss; ++j)
                    for (int i = 0; i < ss; ++i)
                        sum += color[3 * (std::size_t(y * ss + j) * W + (x * ss + i)) + k];
                // Display gamma.
                const double v = std::pow(clamp01(sum * inv), 1.0 / 2.2);
                img.rgb[3 * (std::size_t(y) * img.width + x) + k] = std::uint8_t(std::lround(255.0 * v));
            }
        }
    }
    if (options.legend) drawLegend(img, *options.legend, legend);
    return img;
}

void drawText(Image& image, int x, int y, const std::string& text, const Rgb& colour, int scale) {
    // stb_easy_font writes quads of 4 vertices of 16 bytes, about 270 bytes per character on
    // average; it stops at the buffer's end, so room for 16 quads a character loses nothing.
    std::vector<char> buffer(16 * 64 * text.size() + 64);
    std::string copy = text;
    unsigned char rgba[4] = {colour[0], colour[1], colour[2], 255};
    const int quads = stb_easy_font_print(0.0f, 0.0f, copy.data(), rgba, buffer.data(), int(buffer.size()));
    for (int q = 0; q < quads; ++q) {
        float v[4][4];
        std::memcpy(v, buffer.data() + std::size_t(q) * 64, 64);
        fill(image, x + int(v[0][0] * scale), y + int(v[0][1] * scale), x + int(v[2][0] * scale),
             y + int(v[2][1] * scale), colour);
    }
}

int textWidth(const std::string& text, int scale) {
    std::string copy = text;
    return stb_easy_font_width(copy.data()) * scale;
}

void writePng(const std::string& path, const Image& image, OutputBatch* batch) {
    if (image.width < 1 || image.height < 1 ||
        image.rgb.size() != std::size_t(image.width) * image.height * 3)
        throw Error("cannot write '" + path + "': malformed image");
    writeFileAtomically(path, [&](const std::string& file) {
        // Through a stream of our own: png_image_write_to_file removes its file when a write fails,
        // and the file may be a device written in place.
        std::FILE* out = std::fopen(file.c_str(), "wb");
        if (!out) throw Error("cannot write '" + path + "': " + std::strerror(errno));
        png_image png{};
        png.version = PNG_IMAGE_VERSION;
        png.width = png_uint_32(image.width);
        png.height = png_uint_32(image.height);
        png.format = PNG_FORMAT_RGB;
        bool written = png_image_write_to_stdio(&png, out, 0, image.rgb.data(), 0, nullptr) != 0;
        std::string message = written ? std::string() : std::string(png.message);
        png_image_free(&png);
        if (written && (std::fflush(out) != 0 || std::ferror(out))) {
            written = false;
            message = std::strerror(errno);
        }
        if (std::fclose(out) != 0 && written) {
            written = false;
            message = std::strerror(errno);
        }
        if (!written) throw Error("cannot write '" + path + "': " + message);
    }, batch);
}

void writePicture(const std::string& path, const Mesh& mesh, const PictureOptions& options, OutputBatch* batch) {
    writePng(path, renderPicture(mesh, options), batch);
}

}  // namespace dexelmill
