// The study's log-log plot: deviation against spacing, drawn into an RGB image. Text and the PNG
// come from the io module's picture code.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "dexelmill/error.h"
#include "dexelmill/io/picture.h"
#include "dexelmill/study/study.h"

namespace dexelmill {

namespace {

class Canvas {
public:
    Canvas(int w, int h) {
        img_.width = w;
        img_.height = h;
        img_.rgb.assign(std::size_t(3) * w * h, 255);
    }
    void dot(int x, int y, Rgb c, int size = 1) {
        for (int dy = -size / 2; dy <= size / 2; ++dy)
            for (int dx = -size / 2; dx <= size / 2; ++dx) put(x + dx, y + dy, c);
    }
    /// A line `width` pixels wide; with `dash` > 0, drawn and left blank by turns every `dash` / 2
    /// pixels along it.
    void line(double x0, double y0, double x1, double y1, Rgb c, int width, int dash = 0) {
        const double len = std::hypot(x1 - x0, y1 - y0);
        const int n = std::max(1, int(len * 2));
        for (int i = 0; i <= n; ++i) {
            if (dash > 0 && (i / dash) % 2) continue;
            const double t = double(i) / n;
            dot(int(std::lround(x0 + t * (x1 - x0))), int(std::lround(y0 + t * (y1 - y0))), c, width);
        }
    }
    /// Text with its top-left corner at (x, y), scaled by `scale`.
    void text(int x, int y, const std::string& s, Rgb c, int scale = 2) { drawText(img_, x, y, s, c, scale); }
    static int textWidth(const std::string& s, int scale = 2) { return dexelmill::textWidth(s, scale); }
    const Image& image() const { return img_; }

private:
    void put(int x, int y, Rgb c) {
        if (x < 0 || y < 0 || x >= img_.width || y >= img_.height) return;
        std::uint8_t* p = &img_.rgb[3 * (std::size_t(y) * img_.width + x)];
        std::copy(c.begin(), c.end(), p);
    }
    Image img_;
};

std::string fmt(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

}  // namespace

void writeStudyPlot(const std::string& path, const StudyResult& result, OutputBatch* batch) {
    if (result.runs.empty()) throw Error("study plot: no runs to plot");
    const int W = 1000, H = 720, left = 110, right = 230, top = 84, bottom = 80;
    Canvas c(W, H);
    // The statistics drawn per family set, each with its line style (dash period in pixels).
    struct Stat {
        const char* name;
        double StudyRun::*value;
        int dash;
    };
    // Over the points away from the stock's faces: the block's own edges and the rims where cuts
    // meet them would otherwise set every maximum.
    const Stat stats[] = {{"max", &StudyRun::innerMaxMm, 0}, {"p95", &StudyRun::innerP95Mm, 24}, {"rms", &StudyRun::innerRmsMm, 8}};
    double hMin = 1e300, hMax = 0, eMin = 1e300, eMax = 0;
    std::vector<double> spacings;
    for (const StudyRun& r : result.runs) {
        hMin = std::min(hMin, r.h);
        hMax = std::max(hMax, r.h);
        if (std::find(spacings.begin(), spacings.end(), r.h) == spacings.end()) spacings.push_back(r.h);
        for (const Stat& st : stats)
            if (r.*st.value > 0) {
                eMin = std::min(eMin, r.*st.value);
                eMax = std::max(eMax, r.*st.value);
            }
    }
    if (eMax <= 0) eMin = 1e-3, eMax = 1;
    // Spacings: the data with a margin of a third of a decade on the left and right. Errors: whole
    // decades around the data.
    const double lx0 = std::log10(hMin) - 1.0 / 3.0, lx1 = std::log10(hMax) + 1.0 / 3.0;
    const double ly0 = std::floor(std::log10(eMin)), ly1 = std::max(ly0 + 1, std::ceil(std::log10(eMax)));
    auto X = [&](double h) { return left + (std::log10(h) - lx0) / (lx1 - lx0) * (W - left - right); };
    auto Y = [&](double e) { return H - bottom - (std::log10(e) - ly0) / (ly1 - ly0) * (H - top - bottom); };
    const Rgb grid{225, 225, 225}, axis{60, 60, 60};
    for (double d = std::floor(lx0); d <= lx1; ++d)
        for (int m = 1; m < 10; ++m) {
            const double x = m * std::pow(10, d);
            if (std::log10(x) >= lx0 && std::log10(x) <= lx1) c.line(X(x), top, X(x), H - bottom, grid, 1);
        }
    // The x axis is labelled at the spacings studied, where the points are.
    for (double h : spacings) {
        const std::string label = fmt(h);
        c.line(X(h), H - bottom, X(h), H - bottom + 6, axis, 1);
        c.text(int(X(h)) - Canvas::textWidth(label) / 2, H - bottom + 12, label, axis);
    }
    for (double d = ly0; d <= ly1; ++d) {
        for (int m = 1; m < 10 && d + std::log10(m) <= ly1; ++m) c.line(left, Y(m * std::pow(10, d)), W - right, Y(m * std::pow(10, d)), grid, 1);
        const std::string label = fmt(std::pow(10, d));
        c.text(left - 12 - Canvas::textWidth(label), int(Y(std::pow(10, d))) - 6, label, axis);
    }
    c.line(left, top, left, H - bottom, axis, 2);
    c.line(left, H - bottom, W - right, H - bottom, axis, 2);
    c.text(left, 8, "surface deviation against lattice spacing: " + result.subject, axis);
    c.text(left, 30, "(points on the mesh at least one spacing from the stock's faces)", axis);
    c.text((W - right + left) / 2 - 100, H - 36, "lattice spacing h (mm)", axis);
    c.text(12, top - 24, "deviation (mm)", axis);

    const Rgb palette[] = {{200, 40, 40}, {30, 90, 200}, {30, 150, 60}, {150, 60, 180}, {230, 140, 20}, {20, 160, 170}, {110, 110, 110}};
    std::vector<std::string> families;
    for (const StudyRun& r : result.runs)
        if (std::find(families.begin(), families.end(), r.families) == families.end()) families.push_back(r.families);
    int legendY = top + 10;
    for (std::size_t f = 0; f < families.size(); ++f) {
        const Rgb col = palette[f % (sizeof palette / sizeof palette[0])];
        std::vector<const StudyRun*> rs;
        for (const StudyRun& r : result.runs)
            if (r.families == families[f]) rs.push_back(&r);
        std::sort(rs.begin(), rs.end(), [](auto* a, auto* b) { return a->h < b->h; });
        for (const Stat& st : stats) {
            auto val = [&](const StudyRun* r) { return r->*st.value; };
            for (std::size_t i = 0; i < rs.size(); ++i) {
                if (val(rs[i]) <= 0) continue;
                c.dot(int(X(rs[i]->h)), int(Y(val(rs[i]))), col, 7);
                if (i > 0 && val(rs[i - 1]) > 0)
                    c.line(X(rs[i - 1]->h), Y(val(rs[i - 1])), X(rs[i]->h), Y(val(rs[i])), col, 2, st.dash);
            }
            c.line(W - right + 20, legendY + 6, W - right + 60, legendY + 6, col, 2, st.dash);
            c.text(W - right + 68, legendY, families[f] + " " + st.name, axis);
            legendY += 24;
        }
        legendY += 8;
    }
    writePng(path, c.image(), batch);
}

}  // namespace dexelmill
