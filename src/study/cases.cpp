// The built-in study cases: small programs made in memory whose exact result is known to the
// oracle, each stressing what one dexel direction cannot hold.
#include <cmath>

#include "dexelmill/error.h"
#include "dexelmill/study/study.h"
#include "dexelmill/tool/builders.h"

namespace dexelmill {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Builds a tool path move by move.
class PathBuilder {
public:
    explicit PathBuilder(Program& p, const std::string& name) : p_(p) { p_.path.files.push_back(name); }
    void tool(int n) {
        tool_ = n;
        p_.path.toolChanges.push_back({p_.path.moves.size(), n, {0, line_}});
    }
    void axis(const Vec3& a) { axis_ = glm::normalize(a); }
    void rapid(const Vec3& to) { add(to, true); }
    void feed(const Vec3& to) { add(to, false); }
    void jump(const Vec3& to) { at_ = to; }

private:
    void add(const Vec3& to, bool rapid) {
        Move m;
        m.start = at_;
        m.end = to;
        m.axis = axis_;
        m.tool = tool_;
        m.rapid = rapid;
        m.source = {0, ++line_};
        p_.path.moves.push_back(m);
        at_ = to;
    }
    Program& p_;
    Vec3 at_{0.0};
    Vec3 axis_{0, 0, 1};
    int tool_ = 0;
    int line_ = 0;
};

StudyCase tiltedSlot() {
    StudyCase c{"tilted-slot", "flat D8 tilted 30 degrees about x cutting a slot through a 60 x 40 x 30 block: "
                               "one wall overhangs the slot", {}, Box{Vec3(0, 0, 0), Vec3(60, 40, 30)}};
    c.program.tools.emplace(1, flatEndMill(8, {40, 60}));
    PathBuilder b(c.program, "case:tilted-slot");
    const double t = 30 * kPi / 180;
    const Vec3 axis(0, std::sin(t), std::cos(t));
    b.tool(1);
    b.axis(axis);
    const Vec3 tip(-10, 14, 18);
    b.jump(tip + 50.0 * axis);
    b.rapid(tip + 5.0 * axis);
    b.feed(tip);
    b.feed(tip + Vec3(80, 0, 0));
    b.feed(tip + Vec3(80, 0, 0) + 50.0 * axis);
    return c;
}

StudyCase bullUndercut() {
    StudyCase c{"bull-undercut", "bull-nose D10 r2 pocket 15 mm deep in a 60 x 60 x 30 block, floor rastered "
                                 "upright, then every wall cut with the tool leaning 20 degrees into the pocket: "
                                 "the walls overhang the floor", {}, Box{Vec3(0, 0, 0), Vec3(60, 60, 30)}};
    c.program.tools.emplace(1, bullNoseEndMill(10, 2, {35, 50}));
    PathBuilder b(c.program, "case:bull-undercut");
    b.tool(1);
    const double floor = 15, safe = 40;
    b.jump(Vec3(18, 18, safe));
    b.feed(Vec3(18, 18, floor));
    bool forward = true;
    for (double y = 18; y <= 42 + 1e-9; y += 4) {
        b.feed(Vec3(forward ? 18 : 42, y, floor));
        b.feed(Vec3(forward ? 42 : 18, y, floor));
        forward = !forward;
    }
    b.rapid(Vec3(30, 30, safe));
    // Walls: the tip runs along each wall 0.5 mm above the floor while the tool leans inwards.
    const double lean = 20 * kPi / 180, s = std::sin(lean), k = std::cos(lean);
    struct Wall {
        Vec3 from, to, axis;
    };
    const double z = floor + 0.5;
    for (const Wall& w : {Wall{{46, 18, z}, {46, 42, z}, {-s, 0, k}}, Wall{{42, 46, z}, {18, 46, z}, {0, -s, k}},
                          Wall{{14, 42, z}, {14, 18, z}, {s, 0, k}}, Wall{{18, 14, z}, {42, 14, z}, {0, s, k}}}) {
        b.axis(w.axis);
        b.rapid(w.from + 25.0 * glm::normalize(w.axis));
        b.feed(w.from);
        b.feed(w.to);
        b.feed(w.to + 25.0 * glm::normalize(w.axis));
    }
    return c;
}

StudyCase ballRaster() {
    StudyCase c{"ball-raster", "ball D6 raster finish of a wavy surface in a 50 x 40 x 20 block (stepover 1.5 mm)",
                {}, Box{Vec3(0, 0, 0), Vec3(50, 40, 20)}};
    c.program.tools.emplace(1, ballEndMill(6, {20, 30}));
    PathBuilder b(c.program, "case:ball-raster");
    b.tool(1);
    const double r = 3;
    auto surface = [](double x, double y) { return 12 + 3 * std::sin(x / 8) * std::cos(y / 7); };
    // The tip height where the ball touches the surface: the highest ball-centre height over
    // the footprint, sampled on rings.
    auto tip = [&](double x, double y) {
        double centre = surface(x, y) + r;
        for (int i = 1; i <= 6; ++i) {
            const double rho = r * i / 6;
            for (int k = 0; k < 8 * i; ++k) {
                const double a = 2 * kPi * k / (8 * i);
                centre = std::max(centre, surface(x + rho * std::cos(a), y + rho * std::sin(a)) +
                                              std::sqrt(std::max(0.0, r * r - rho * rho)));
            }
        }
        return centre - r;
    };
    b.jump(Vec3(-4, -2, 30));
    bool forward = true;
    for (double y = -2; y <= 42 + 1e-9; y += 1.5) {
        for (int i = 0; i <= 54; ++i) {
            const double x = forward ? -2 + i : 52 - i;
            const Vec3 p(x, y, tip(x, y));
            if (i == 0 && y == -2) b.rapid(Vec3(p.x, p.y, 30));
            b.feed(p);
        }
        forward = !forward;
    }
    return c;
}

StudyCase vCarve() {
    StudyCase c{"v-carve", "60-degree V-bit engraving a wave and a ring of varying depth in a 60 x 30 x 10 block",
                {}, Box{Vec3(0, 0, 0), Vec3(60, 30, 10)}};
    c.program.tools.emplace(1, chamferMill(0, 30 * kPi / 180, 8, {15, 25}));
    PathBuilder b(c.program, "case:v-carve");
    b.tool(1);
    b.jump(Vec3(5, 15, 15));
    b.rapid(Vec3(5, 15, 11));
    for (int i = 0; i <= 100; ++i) {
        const double x = 5 + 0.5 * i;
        b.feed(Vec3(x, 15 + 8 * std::sin(x / 5), 10 - 1.0 - 1.5 * (0.5 + 0.5 * std::sin(x / 7))));
    }
    b.rapid(Vec3(55, 15, 15));
    b.rapid(Vec3(40, 15, 15));
    for (int i = 0; i <= 72; ++i) {
        const double a = 2 * kPi * i / 72;
        b.feed(Vec3(30 + 10 * std::cos(a), 15 + 10 * std::sin(a), 10 - 2 - std::cos(3 * a)));
    }
    b.rapid(Vec3(40, 15, 15));
    return c;
}

}  // namespace

std::vector<std::string> studyCaseNames() { return {"tilted-slot", "bull-undercut", "ball-raster", "v-carve"}; }

StudyCase studyCase(const std::string& name) {
    if (name == "tilted-slot") return tiltedSlot();
    if (name == "bull-undercut") return bullUndercut();
    if (name == "ball-raster") return ballRaster();
    if (name == "v-carve") return vCarve();
    std::string names;
    for (const std::string& n : studyCaseNames()) names += (names.empty() ? "" : ", ") + n;
    throw Error("no built-in case '" + name + "'; the cases are " + names);
}

}  // namespace dexelmill
