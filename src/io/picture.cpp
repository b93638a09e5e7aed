#include "dexelmill/io/picture.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <png.h>

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

}  // namespace

Image renderPicture(const Mesh& mesh, const PictureOptions& options) {
    if (options.width < 1 || options.height < 1 || options.width > 16384 || options.height > 16384)
        throw Error("picture size must be between 1 and 16384 pixels");
    if (options.supersample < 1 || options.supersample > 4)
        throw Error("picture supersampling must be 1 to 4");
    if (!(glm::length(options.viewDirection) > 0.0)) throw Error("picture view direction is zero");

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
    const double sx = (xmax - xmin) > 0 ? usable * W / (xmax - xmin) : 1.0;
    const double sy = (ymax - ymin) > 0 ? usable * H / (ymax - ymin) : 1.0;
    cam.scale = std::min(sx, sy);
    cam.x0 = 0.5 * (xmin + xmax) - 0.5 * W / cam.scale;
    cam.y0 = 0.5 * (ymin + ymax) + 0.5 * H / cam.scale;

    // Lights in view space terms: key from upper left, fill from the right, both towards the
    // viewer; Blinn-Phong specular on the key light.
    const Vec3 key = glm::normalize(-0.6 * cam.right + 0.6 * cam.up + 0.55 * cam.back);
    const Vec3 fill = glm::normalize(0.7 * cam.right - 0.2 * cam.up + 0.7 * cam.back);
    const Vec3 halfKey = glm::normalize(key + cam.back);
    const Vec3 base(0.62, 0.66, 0.72);  // light steel

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
    return img;
}

void writePng(const std::string& path, const Image& image) {
    if (image.width < 1 || image.height < 1 ||
        image.rgb.size() != std::size_t(image.width) * image.height * 3)
        throw Error("cannot write '" + path + "': malformed image");
    writeFileAtomically(path, [&](const std::string& temp) {
        png_image png{};
        png.version = PNG_IMAGE_VERSION;
        png.width = png_uint_32(image.width);
        png.height = png_uint_32(image.height);
        png.format = PNG_FORMAT_RGB;
        if (!png_image_write_to_file(&png, temp.c_str(), 0, image.rgb.data(), 0, nullptr)) {
            const std::string message = png.message;
            png_image_free(&png);
            throw Error("cannot write '" + path + "': " + message);
        }
        png_image_free(&png);
    });
}

void writePicture(const std::string& path, const Mesh& mesh, const PictureOptions& options) {
    writePng(path, renderPicture(mesh, options));
}

}  // namespace dexelmill
