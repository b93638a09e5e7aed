/// @file common.cpp
/// @brief Shared helpers of the readers: arcs, numbers, files.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "dexelmill/error.h"
#include "path/detail/arc.h"
#include "path/detail/text.h"

namespace dexelmill::detail {

namespace {
constexpr double kHalfTurn = 3.14159265358979323846;
}

double chordSag(double radius, double sweep, std::size_t segments) {
    if (segments == 0) return 0.0;
    return radius * (1.0 - std::cos(std::abs(sweep) / double(segments) / 2.0));
}

std::size_t arcSegments(double radius, double sweep, double tolerance, std::size_t maxSegments) {
    const double a = std::abs(sweep);
    if (!(a > 0.0) || !(radius > 0.0)) return 1;
    // A tolerance of r or more still takes no chord wider than a half turn: the arc beyond a
    // half turn bulges past the chord's ends, and a full circle's one chord has no length at all.
    const double maxStep = tolerance >= radius ? kHalfTurn : 2.0 * std::acos(1.0 - tolerance / radius);
    const double n = std::ceil(a / maxStep - 1e-12);
    if (!(n <= double(maxSegments))) return 0;
    return std::max<std::size_t>(1, std::size_t(n));
}

void arcPoints(const ArcSpec& arc, std::size_t segments, std::vector<Vec3>& out) {
    for (std::size_t i = 1; i <= segments; ++i) {
        const double t = double(i) / double(segments);
        const double a = arc.startAngle + arc.sweep * t;
        const double r = arc.startRadius + (arc.endRadius - arc.startRadius) * t;
        const double h = arc.startHeight + (arc.endHeight - arc.startHeight) * t;
        out.push_back(arc.centre + r * (std::cos(a) * arc.u + std::sin(a) * arc.v) + h * arc.w);
    }
}

namespace {
constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                             1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                             1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
}

bool parseUnsignedDecimal(std::string_view s, std::size_t& pos, double& value) {
    const std::size_t start = pos;
    std::uint64_t mant = 0;
    int digits = 0, fracDigits = 0;
    bool any = false, overflow = false, dot = false;
    std::size_t i = pos;
    for (; i < s.size(); ++i) {
        const char c = s[i];
        if (c >= '0' && c <= '9') {
            any = true;
            if (mant == 0 && c == '0') {
                if (dot) ++fracDigits;
                continue;  // leading zeros carry no precision
            }
            if (digits < 19) {
                mant = mant * 10 + std::uint64_t(c - '0');
                ++digits;
                if (dot) ++fracDigits;
            } else {
                overflow = true;

            }
        } else if (c == '.' && !dot) {
            dot = true;
        } else {
            break;
        }
    }
    if (!any) return false;
    pos = i;
    if (!overflow && fracDigits <= 22 && mant < (std::uint64_t(1) << 53)) {
        value = double(mant) / kPow10[fracDigits];
        return true;
    }
    const std::string tmp(s.substr(start, i - start));
    value = std::strtod(tmp.c_str(), nullptr);
    return true;
}

std::string readTextFile(const std::string& path) {
    // Only regular files: a directory reads as nothing, and /dev/zero or a FIFO never ends.
    std::error_code ec;
    const std::filesystem::file_status st = std::filesystem::status(path, ec);
    if (ec || !std::filesystem::exists(st)) throw Error("cannot open '" + path + "': no such file");
    if (std::filesystem::is_directory(st)) throw Error("'" + path + "' is a directory, not a program file");
    if (!std::filesystem::is_regular_file(st))
        throw Error("'" + path + "' is not a regular file (a device, pipe or socket); programs are read from files");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot open '" + path + "'");
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw Error("cannot read '" + path + "'");
    return normaliseText(ss.str());
}

std::string normaliseText(std::string text) {
    // A UTF-8 byte-order mark, as Windows editors write it, is not part of the text.
    if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.erase(0, 3);
    // Lone CR line ends (old Mac editors) become LF; CRLF stays, and the readers drop its CR.
    for (std::size_t i = text.find('\r'); i != std::string::npos; i = text.find('\r', i + 1))
        if (i + 1 == text.size() || text[i + 1] != '\n') text[i] = '\n';
    return text;
}

std::optional<std::string> readFileIfAny(const FileSource& files, const std::string& path) {
    if (files) {
        std::optional<std::string> text = files(path);
        if (text) return normaliseText(std::move(*text));
        return std::nullopt;
    }
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return std::nullopt;
    return readTextFile(path);
}

std::string readFile(const FileSource& files, const std::string& path) {
    std::optional<std::string> text = readFileIfAny(files, path);
    if (!text) throw Error("cannot open '" + path + "': no such file");
    return std::move(*text);
}

std::string directoryOf(const std::string& path) {
    const auto p = path.find_last_of('/');
    return p == std::string::npos ? std::string() : path.substr(0, p);
}

std::string joinPath(const std::string& dir, const std::string& name) {
    if (dir.empty() || (!name.empty() && name[0] == '/')) return name;
    return dir + "/" + name;
}

std::string tooManyMoves(std::size_t limit, const std::string& reason) {
    std::string m = "program makes more than " + std::to_string(limit) + " moves";
    if (!reason.empty()) m += ": " + reason;
    return m;
}

std::string formatNumber(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

std::string formatPoint(const Vec3& p) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "(%.6g, %.6g, %.6g)", p.x, p.y, p.z);
    return buf;
}

}  // namespace dexelmill::detail
