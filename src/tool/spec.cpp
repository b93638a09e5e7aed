#include "dexelmill/tool/spec.h"

#include <map>
#include <optional>
#include <sstream>
#include <vector>

#include "dexelmill/decimal.h"
#include "dexelmill/error.h"
#include "dexelmill/tool/builders.h"

namespace dexelmill {

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> out;
    std::size_t start = 0;
    for (std::size_t i = 0; i <= s.size(); ++i) {
        if (i == s.size() || s[i] == sep) {
            out.push_back(s.substr(start, i - start));
            start = i + 1;
        }
    }
    return out;
}

double number(const std::string& spec, const std::string& text) {
    const std::optional<double> v = parseDecimal(text);
    if (!v) throw Error("tool '" + spec + "': '" + text + "' is not a number");
    return *v;
}

}  // namespace

Tool parseToolSpec(const std::string& spec) {
    const std::size_t colon = spec.find(':');
    if (colon == std::string::npos)
        throw Error("tool '" + spec + "': expected KIND:PARAMETERS, e.g. ball:d=6 or bull:d=10,r=2");
    const std::string kind = spec.substr(0, colon);
    const std::vector<std::string> parts = split(spec.substr(colon + 1), ',');

    // Positional values (apt) and named ones (everything else, and length/total everywhere).
    std::vector<double> positional;
    std::map<std::string, double> named;
    for (const std::string& p : parts) {
        const std::size_t eq = p.find('=');
        if (eq == std::string::npos) {
            if (!named.empty()) throw Error("tool '" + spec + "': positional value '" + p + "' after named ones");
            positional.push_back(number(spec, p));
        } else {
            const std::string key = p.substr(0, eq);
            if (named.count(key)) throw Error("tool '" + spec + "': '" + key + "' is given twice");
            named[key] = number(spec, p.substr(eq + 1));
        }
    }
    if (kind != "apt" && !positional.empty())
        throw Error("tool '" + spec + "': write parameters as name=value, e.g. d=6");
    auto take = [&](const char* key, std::optional<double> fallback = std::nullopt) {
        const auto it = named.find(key);
        if (it == named.end()) {
            if (fallback) return *fallback;
            throw Error("tool '" + spec + "': missing " + key + "=");
        }
        const double v = it->second;
        named.erase(it);
        return v;
    };
    // ToolLengths reads 0 as "not given": a 0 written out is a tool without flutes or without a
    // body, which no tool is, not a request for the default.
    for (const char* key : {"length", "total"}) {
        const auto given = named.find(key);
        if (given != named.end() && !(given->second > 0.0)) {
            std::ostringstream got;
            got << given->second;
            throw Error("tool '" + spec + "': " + key + " must be positive, got " + got.str());
        }
    }
    ToolLengths lengths;
    lengths.cutting = take("length", 0.0);
    lengths.total = take("total", 0.0);
    // A holder needs both its sizes: neither has a default a machine would share.
    const bool holder = named.count("holder") > 0;
    if (holder != (named.count("holderlength") > 0))
        throw Error("tool '" + spec + "': a holder takes both holder=D and holderlength=L");
    const double holderD = holder ? take("holder") : 0.0, holderLength = holder ? take("holderlength") : 0.0;

    auto finish = [&](Tool t) {
        if (!named.empty()) throw Error("tool '" + spec + "': unknown parameter '" + named.begin()->first + "' for " + kind);
        return holder ? withHolder(t, holderD, holderLength) : t;
    };
    if (kind == "ball") return finish(ballEndMill(take("d"), lengths));
    if (kind == "flat") return finish(flatEndMill(take("d"), lengths));
    if (kind == "bull") {
        const double d = take("d"), r = take("r");
        return finish(bullNoseEndMill(d, r, lengths));
    }
    if (kind == "taper") {
        const double d = take("d"), a = take("angle");
        return finish(taperEndMill(d, a * kDegree, lengths));
    }
    if (kind == "chamfer" || kind == "vbit") {
        const double d = take("d"), a = take("angle"), tip = take("tip", 0.0);
        return finish(chamferMill(tip, a * kDegree, d, lengths));
    }
    if (kind == "taperball") {
        const double d = take("d"), a = take("angle");
        return finish(taperBallMill(d, a * kDegree, lengths));
    }
    if (kind == "drill") {
        const double d = take("d"), a = take("angle", 118.0);
        return finish(drill(d, a * kDegree, lengths));
    }
    if (kind == "apt") {
        if (positional.size() != 7)
            throw Error("tool '" + spec + "': apt takes 7 values D,R,E,F,ALPHA,BETA,H, got " +
                        std::to_string(positional.size()));
        if (lengths.total != 0.0) throw Error("tool '" + spec + "': apt takes its total length from H");
        const auto& v = positional;
        return finish(aptCutter(v[0], v[1], v[2], v[3], v[4] * kDegree, v[5] * kDegree, v[6], lengths.cutting));
    }
    throw Error("tool '" + spec + "': unknown kind '" + kind +
                "' (ball, flat, bull, taper, chamfer, vbit, taperball, drill, apt)");
}

}  // namespace dexelmill
