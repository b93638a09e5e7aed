// Writes dexelmill's bundled example programs into a folder (default: the current one):
//
//   hood.ngc       ball-end R25.4 raster finish of a smooth freeform surface, the scale of the
//                  automobile hood in the paper: 1694 x 890 x 870 mm stock, about 16,800 moves.
//   gearbox.apt    three operations on a 1000 x 800 x 440 mm block: fillet-end D100 r10 z-level
//                  roughing, ball D100 semi-finish and ball D50 finish of a housing cavity.
//   tilted.apt     3+2 machining with the tool axis tilted 30 degrees: slots whose walls lean
//                  over the cut (undercuts a z-only dexel model cannot hold).
//
// The programs are ordinary text a user can read and edit; the shapes are smooth analytic
// surfaces so the cutter locations can be computed by sampling without gouging measurably.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

namespace {

constexpr double kPi = 3.14159265358979323846;

using Surface = std::function<double(double, double)>;

/// Height of the centre of a ball of radius r resting on the surface above (x, y), minus r: the
/// tip (cutter-location) height of a ball end mill that touches without gouging. Sampled over
/// the ball's footprint on `rings` rings.
double ballTip(const Surface& s, double x, double y, double r, int rings) {
    double centre = s(x, y) + r;
    for (int i = 1; i <= rings; ++i) {
        const double rho = r * i / rings;
        const int spokes = 6 * i;
        for (int k = 0; k < spokes; ++k) {
            const double a = 2 * kPi * k / spokes;
            const double z = s(x + rho * std::cos(a), y + rho * std::sin(a));
            centre = std::max(centre, z + std::sqrt(std::max(0.0, r * r - rho * rho)));
        }
    }
    return centre - r;
}

/// The highest surface point under a flat-bottomed disk of radius r (a conservative tip height
/// for a bull-nose roughing cutter).
double diskTip(const Surface& s, double x, double y, double r, int rings) {
    double z = s(x, y);
    for (int i = 1; i <= rings; ++i) {
        const double rho = r * i / rings;
        const int spokes = 6 * i;
        for (int k = 0; k < spokes; ++k) {
            const double a = 2 * kPi * k / spokes;
            z = std::max(z, s(x + rho * std::cos(a), y + rho * std::sin(a)));
        }
    }
    return z;
}

double smoothstep(double e0, double e1, double x) {
    const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3 - 2 * t);
}

class Writer {
public:
    explicit Writer(const std::string& path) : path_(path), out_(path) {
        if (!out_) throw std::runtime_error("cannot write " + path);
    }
    template <class... A>
    void line(const char* fmt, A... args) {
        char buf[256];
        std::snprintf(buf, sizeof buf, fmt, args...);
        out_ << buf << '\n';
    }
    void close(long moves) {
        out_.close();
        if (!out_) throw std::runtime_error("failed writing " + path_);
        std::cout << path_ << ": " << moves << " moves\n";
    }

private:
    std::string path_;
    std::ofstream out_;
};

// ---------------------------------------------------------------- hood
void writeHood(const std::string& dir) {
    const double X = 1694, Y = 890, Z = 870, R = 25.4;
    // A hood-like crown: highest along the middle, falling towards the front, back and sides,
    // with a soft central ridge.
    const Surface s = [=](double x, double y) {
        const double u = (x - X / 2) / (X / 2 + 80), v = (y - Y / 2) / (Y / 2 + 60);
        const double crown = (1 - u * u) * (1 - 0.55 * v * v);
        const double ridge = 12 * std::exp(-v * v / 0.02) * (1 - u * u);
        return 745 + 100 * crown + ridge;
    };
    Writer w(dir + "/hood.ngc");
    long moves = 0;
    w.line("(dexelmill example: hood - ball end R25.4 raster finish)");
    w.line("(stock: box 0,0,0 to %.0f,%.0f,%.0f mm; tool 1: ball D50.8)", X, Y, Z);
    w.line("G21 G90 G17 G94");
    w.line("T1 M6");
    w.line("S8000 M3");
    const double safe = Z + 30;
    const int passes = 128, segments = 130;
    const double y0 = 0, dy = Y / (passes - 1), x0 = -10, dx = (X + 20) / segments;
    w.line("G0 Z%.3f", safe);
    ++moves;
    w.line("G0 X%.3f Y%.3f", x0, y0);
    ++moves;
    w.line("G1 Z%.4f F3000", ballTip(s, x0, y0, R, 8));
    ++moves;
    for (int p = 0; p < passes; ++p) {
        const double y = y0 + p * dy;
        if (p > 0) {  // step over at the end of the pass
            const double x = (p % 2) ? x0 + segments * dx : x0;
            w.line("G1 X%.4f Y%.4f Z%.4f", x, y, ballTip(s, x, y, R, 8));
            ++moves;
        }
        for (int i = 1; i <= segments; ++i) {
            const int k = (p % 2) ? segments - i : i;
            const double x = x0 + k * dx;
            w.line("G1 X%.4f Z%.4f", x, ballTip(s, x, y, R, 8));
            ++moves;
        }
    }
    w.line("G0 Z%.3f", safe);
    ++moves;
    w.line("M5");
    w.line("M30");
    w.close(moves);
}

// ---------------------------------------------------------------- gearbox
class AptWriter : public Writer {
public:
    using Writer::Writer;
    long moves = 0;
    bool rapid = false;
    void go(double x, double y, double z) {
        if (rapid) line("RAPID");
        line("GOTO/%.4f,%.4f,%.4f", x, y, z);
        ++moves;
    }
    void goAxis(double x, double y, double z, double i, double j, double k) {
        if (rapid) line("RAPID");
        line("GOTO/%.4f,%.4f,%.4f,%.6f,%.6f,%.6f", x, y, z, i, j, k);
        ++moves;
    }
};

void writeGearbox(const std::string& dir) {
    const double X = 1000, Y = 800, Z = 440;
    // Housing cavity: a rounded basin 180 mm deep with two bearing seats (half cylinders of
    // radius 110 along y) sunk into its floor.
    const Surface s = [=](double x, double y) {
        const double bx = std::max(std::abs(x - X / 2) - 330, 0.0), by = std::max(std::abs(y - Y / 2) - 230, 0.0);
        const double edge = std::sqrt(bx * bx + by * by);        // distance outside the flat floor
        const double basin = 1 - smoothstep(0, 90, edge);        // 1 on the floor, 0 outside
        double z = Z - 180 * basin;
        for (double cx : {300.0, 700.0}) {
            const double d = std::abs(x - cx);
            if (d < 110 && std::abs(y - Y / 2) < 200) {
                const double seat = std::sqrt(110 * 110 - d * d) * smoothstep(200, 170, std::abs(y - Y / 2));
                z = std::min(z, Z - 180 - 0.5 * seat);
            }
        }
        return z;
    };
    AptWriter w(dir + "/gearbox.apt");
    w.line("PARTNO/GEARBOX HOUSING");
    w.line("UNITS/MM");
    w.line("$$ stock: box 0,0,0 to %.0f,%.0f,%.0f mm", X, Y, Z);
    const double safe = Z + 40;

    // Operation 1: z-level roughing with a fillet-end D100 r10, 3 mm stock left.
    w.line("$$ OPERATION 1: ROUGHING, FILLET-END D100 R10");
    w.line("CUTTER/100,10,40,10,0,0,250");
    w.line("LOAD/TOOL,1");
    w.line("SPINDL/2500,RPM,CLW");
    w.line("FEDRAT/2000,MMPM");
    w.rapid = true;
    w.go(0, 0, safe);
    w.rapid = false;
    const double step = 60, ds = 20;
    for (double zl = Z - 20; zl >= Z - 300; zl -= 20) {
        for (double y = 40; y <= Y - 40; y += step) {
            // Feasible runs along x at this level: the cutter fits above the surface + allowance.
            std::vector<std::pair<double, double>> runs;
            double runStart = -1;
            for (double x = 40; x <= X - 40 + 1e-9; x += ds) {
                const bool ok = diskTip(s, x, y, 50, 5) + 3 <= zl;
                if (ok && runStart < 0) runStart = x;
                if ((!ok || x + ds > X - 40 + 1e-9) && runStart >= 0) {
                    const double end = ok ? x : x - ds;
                    if (end > runStart) runs.emplace_back(runStart, end);
                    runStart = -1;
                }
            }
            for (const auto& r : runs) {
                w.rapid = true;
                w.go(r.first, y, safe);
                // Down to just above the previous level, which cleared this run; then feed in.
                w.go(r.first, y, std::min(zl + 20, Z) + 2);
                w.rapid = false;
                for (double x = r.first; x <= r.second + 1e-9; x += ds) w.go(std::min(x, r.second), y, zl);
                w.go(r.second, y, zl);
                w.rapid = true;
                w.go(r.second, y, safe);
                w.rapid = false;
            }
        }
    }
    const long rough = w.moves;

    // Operation 2: ball D100 semi-finish raster, 1 mm stock left.
    w.line("$$ OPERATION 2: SEMI-FINISH, BALL D100");
    w.line("CUTTER/100,50,0,50,0,0,300");
    w.line("LOAD/TOOL,2");
    w.line("SPINDL/3000,RPM,CLW");
    auto raster = [&](double r, double allowance, double stepover, double dx) {
        w.rapid = true;
        w.go(0, 0, safe);
        w.rapid = false;
        bool forward = true;
        bool first = true;
        for (double y = 0; y <= Y + 1e-9; y += stepover) {
            const int n = int(std::round(X / dx));
            for (int i = 0; i <= n; ++i) {
                const double x = forward ? i * dx : X - i * dx;
                const double z = ballTip(s, x, y, r, 8) + allowance;
                if (first) {
                    w.rapid = true;
                    w.go(x, y, safe);
                    w.rapid = false;
                    first = false;
                }
                w.go(x, y, z);
            }
            forward = !forward;
        }
        w.rapid = true;
        w.go(forward ? 0 : X, Y, safe);
        w.rapid = false;
    };
    raster(50, 1.0, 16, 11.1);
    const long semi = w.moves - rough;

    // Operation 3: ball D50 finish raster.
    w.line("$$ OPERATION 3: FINISH, BALL D50");
    w.line("CUTTER/50,25,0,25,0,0,250");
    w.line("LOAD/TOOL,3");
    w.line("SPINDL/6000,RPM,CLW");
    raster(25, 0.0, 12, 12.8);
    w.line("FINI");
    std::cout << "  roughing " << rough << ", semi-finish " << semi << ", finish " << w.moves - rough - semi
              << "\n";
    w.close(w.moves);
}

// ---------------------------------------------------------------- tilted
void writeTilted(const std::string& dir) {
    const double X = 120, Y = 80, Z = 50;
    AptWriter w(dir + "/tilted.apt");
    w.line("PARTNO/TILTED 3+2 SLOTS");
    w.line("UNITS/MM");
    w.line("$$ stock: box 0,0,0 to %.0f,%.0f,%.0f mm", X, Y, Z);
    w.line("CUTTER/10,0,5,0,0,0,70");
    w.line("LOAD/TOOL,1");
    w.line("MULTAX");
    const double t = 30 * kPi / 180;
    // Two slots along x. The first leans towards +y, the second towards -y: each has one wall
    // overhanging the slot floor.
    struct Slot {
        double y, lean;
    };
    for (const Slot& slot : {Slot{22, 1.0}, Slot{58, -1.0}}) {
        const double i = 0, j = slot.lean * std::sin(t), k = std::cos(t);
        const double depthStep = 3, depth = 18, clearance = 3;
        for (double d = depthStep; d <= depth + 1e-9; d += depthStep) {
            // The tip runs d below the top face; it enters and leaves along the tool axis, from
            // and to a point where the tip is `clearance` above the stock, so the whole tool is
            // clear of material during the rapids.
            const double zTip = Z - d, yTip = slot.y - j * d / k;
            const double up = (d + clearance) / k;  // distance along the axis to clear the top
            auto above = [&](double x, double y) {
                w.goAxis(x + i * up, y + j * up, zTip + k * up, i, j, k);
            };
            w.rapid = true;
            above(10, yTip);
            w.rapid = false;
            w.goAxis(10, yTip, zTip, i, j, k);
            w.goAxis(X - 10, yTip, zTip, i, j, k);
            // Widen the slot by a second pass 4 mm across.
            w.goAxis(X - 10, yTip + 4, zTip, i, j, k);
            w.goAxis(10, yTip + 4, zTip, i, j, k);
            above(10, yTip + 4);
        }
    }
    w.line("FINI");
    w.close(w.moves);
}

}  // namespace

int main(int argc, char** argv) {
    const std::string dir = argc > 1 ? argv[1] : ".";
    if (argc > 2 || (argc == 2 && (std::string(argv[1]) == "-h" || std::string(argv[1]) == "--help"))) {
        std::cout << "usage: make_examples [DIR]\n"
                     "Writes the bundled example programs hood.ngc, gearbox.apt and tilted.apt into DIR\n"
                     "(default: the current folder).\n";
        return argc > 2 ? 2 : 0;
    }
    try {
        writeHood(dir);
        writeGearbox(dir);
        writeTilted(dir);
    } catch (const std::exception& e) {
        std::cerr << "make_examples: error: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
