#include "dexelmill/machine/kinematics.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "dexelmill/error.h"
#include "dexelmill/io/json_text.h"
#include "dexelmill/geometry/rotation.h"
#include "dexelmill/geometry/tolerance.h"

namespace dexelmill {

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

/// The tables' turns seen from the part (turn 0 outermost): the part frame is the machine frame
/// carried back through the tables, innermost (next to the part) first, each by minus its angle.
std::vector<RotaryTurn> tableTurns(const Machine& m, const RotaryAngles& from, const RotaryAngles& to) {
    std::vector<RotaryTurn> turns;
    for (std::size_t i = m.axes.size(); i-- > 0;) {
        const RotaryAxisSpec& a = m.axes[i];
        if (!a.onTable) continue;
        turns.push_back({a.direction, a.pivot, -from[a.letter] * kDegree, -to[a.letter] * kDegree});
    }
    return turns;
}

/// The heads' turns, from the base out to the tool, each by its angle (pivots relative to the tip).
std::vector<RotaryTurn> headTurns(const Machine& m, const RotaryAngles& from, const RotaryAngles& to) {
    std::vector<RotaryTurn> turns;
    for (const RotaryAxisSpec& a : m.axes)
        if (!a.onTable) turns.push_back({a.direction, a.pivot, from[a.letter] * kDegree, to[a.letter] * kDegree});
    return turns;
}

/// The turns applied to a point, innermost (last) first, at their start angles.
Vec3 applyTurns(const std::vector<RotaryTurn>& turns, Vec3 x, bool aboutPivot) {
    for (std::size_t i = turns.size(); i-- > 0;) {
        const RotaryTurn& t = turns[i];
        x = aboutPivot ? t.pivot + rotateAbout(x - t.pivot, t.direction, t.from) : rotateAbout(x, t.direction, t.from);
    }
    return x;
}

/// Where the heads put the tip relative to the joints: the tip at zero turned about each head's
/// pivot, from the tool side in.
Vec3 headOffset(const Machine& m, const RotaryAngles& angles) {
    return applyTurns(headTurns(m, angles, angles), Vec3(0.0), true);
}

/// The head turns' rotation applied to the tool's own axis.
Vec3 headAxis(const Machine& m, const RotaryAngles& angles) {
    return applyTurns(headTurns(m, angles, angles), Vec3(0.0, 0.0, 1.0), false);
}

Machine builtin(const std::string& name) {
    Machine m;
    m.name = name;
    if (name == "xyzac-trt") {
        // LinuxCNC's xyzac-trt-kins with y-offset 20, z-offset 10, rot-points 0, conventional
        // directions 0: part = Rz(-C) (D + Rx(-A) (joints - D)), D = (0, 20, 10).
        m.axes = {{'A', true, {1, 0, 0}, {0, 20, 10}}, {'C', true, {0, 0, 1}, {0, 0, 0}}};
    } else if (name == "xyzbc-trt") {
        // LinuxCNC's xyzbc-trt-kins with x-offset -20, z-offset -15 (its sim config's values):
        // part = Rz(-C) (D + Ry(-B) (joints - D)), D = (-20, 0, -15).
        m.axes = {{'B', true, {0, 1, 0}, {-20, 0, -15}}, {'C', true, {0, 0, 1}, {0, 0, 0}}};
    } else if (name == "xyza") {
        m.axes = {{'A', true, {1, 0, 0}, {0, 0, 0}}};
    } else {
        m.name.clear();
    }
    return m;
}

/// The three numbers of j, the value at `pointer`.
Vec3 readVector(const nlohmann::json& j, const std::string& what, const JsonPlaces& places, const std::string& pointer) {
    if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() || !j[2].is_number())
        throw ParseError(places.value(pointer), what + " must be an array of three numbers", j.dump());
    const Vec3 v(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        throw ParseError(places.value(pointer), what + " must be finite", j.dump());
    return v;
}

/// A string field of object j (at `pointer`), `fallback` where it is absent.
std::string readString(const nlohmann::json& j, const char* key, const std::string& fallback, const std::string& what,
                       const JsonPlaces& places, const std::string& pointer) {
    if (!j.contains(key)) return fallback;
    if (!j[key].is_string())
        throw ParseError(places.value(pointer + "/" + key), what + "\"" + key + "\" must be a string", j[key].dump());
    return j[key].get<std::string>();
}

/// Refuses a key of object j (at `pointer`) outside `known`: a misspelt "pivot" would leave the
/// pivot at the origin unnoticed.
void onlyKnownKeys(const nlohmann::json& j, std::initializer_list<const char*> known, const std::string& what,
                   const JsonPlaces& places, const std::string& pointer) {
    for (auto it = j.begin(); it != j.end(); ++it)
        if (std::none_of(known.begin(), known.end(), [&](const char* k) { return it.key() == k; })) {
            std::string names;
            for (const char* k : known) names += std::string(names.empty() ? "" : ", ") + "\"" + k + "\"";
            throw ParseError(places.key(pointer + "/" + jsonPointerToken(it.key())),
                             what + "unknown key \"" + it.key() + "\" (known: " + names + ")", it.key());
        }
}

}  // namespace

bool Machine::has(char letter) const {
    for (const RotaryAxisSpec& a : axes)
        if (a.letter == letter) return true;
    return false;
}

Vec3 Machine::toolAxis(const RotaryAngles& angles) const {
    return glm::normalize(applyTurns(tableTurns(*this, angles, angles), headAxis(*this, angles), false));
}

Vec3 Machine::partFromJoints(const Vec3& joints, const RotaryAngles& angles) const {
    return applyTurns(tableTurns(*this, angles, angles), joints + headOffset(*this, angles), true);
}

Vec3 Machine::jointsFromPart(const Vec3& tip, const RotaryAngles& angles) const {
    // Undo the tables' turns, outermost first, each by its own angle's opposite.
    Vec3 x = tip;
    for (const RotaryTurn& t : tableTurns(*this, angles, angles)) x = t.pivot + rotateAbout(x - t.pivot, t.direction, -t.from);
    return x - headOffset(*this, angles);
}

bool Machine::headsStill(const RotaryAngles& from, const RotaryAngles& to) const {
    for (const RotaryAxisSpec& a : axes)
        if (!a.onTable && from[a.letter] != to[a.letter]) return false;
    return true;
}

RotaryMotion Machine::motion(const RotaryAngles& from, const RotaryAngles& to, bool tcp, const Vec3& jointsFrom,
                             const Vec3& jointsTo) const {
    RotaryMotion r;
    r.turns = tableTurns(*this, from, to);
    if (tcp) {
        // The axis is Q_tables Q_heads z: the heads' turns follow the tables' in the chain.
        for (const RotaryTurn& t : headTurns(*this, from, to)) r.turns.push_back(t);
        r.toolAxis = Vec3(0.0, 0.0, 1.0);
        return r;
    }
    r.tipCarried = true;
    if (!headsStill(from, to)) {
        // A head turns: its pivot travels with the joints, and the tool turns about it.
        r.headTurns = headTurns(*this, from, to);
        r.machineStart = jointsFrom;
        r.machineEnd = jointsTo;
        return r;
    }
    // The heads stand still: they fix the tool's axis and the tip's offset from the joints.
    r.toolAxis = headAxis(*this, from);
    r.machineStart = jointsFrom + headOffset(*this, from);
    r.machineEnd = jointsTo + headOffset(*this, to);
    return r;
}

std::vector<std::string> builtinMachineNames() { return {"xyzac-trt", "xyzbc-trt", "xyza"}; }

Machine parseMachine(const std::string& text, const std::string& fileName) {
    if (const std::optional<JsonTextFault> fault = jsonTextFault(text, /*comments=*/false))
        throw ParseError(locateByte(text, fault->byte, fileName), "machine description: " + fault->message);
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        // The library's offset counts the faulty character as read.
        throw ParseError(locateByte(text, e.byte > 0 ? e.byte - 1 : 0, fileName),
                         "not valid JSON for a machine description");
    } catch (const nlohmann::json::exception& e) {
        // Valid syntax the library still refuses; a number beyond double's range is found above.
        throw ParseError(SourceLocation{fileName, 0, 0},
                         std::string("not valid JSON for a machine description: ") + e.what());
    }
    const JsonPlaces places(text, fileName, false);
    if (!j.is_object()) throw ParseError(places.value(""), "a machine description must be a JSON object");
    onlyKnownKeys(j, {"name", "tcp_at_start", "axes"}, "", places, "");
    Machine m;
    m.name = readString(j, "name", fileName, "", places, "");
    if (j.contains("tcp_at_start")) {
        if (!j["tcp_at_start"].is_boolean())
            throw ParseError(places.value("/tcp_at_start"), "\"tcp_at_start\" must be true or false");
        m.tcpAtStart = j["tcp_at_start"].get<bool>();
    }
    if (!j.contains("axes") || !j["axes"].is_array() || j["axes"].empty())
        throw ParseError(places.value(j.contains("axes") ? "/axes" : ""),
                         "a machine description needs \"axes\": a non-empty array of rotary axes");
    for (std::size_t i = 0; i < j["axes"].size(); ++i) {
        const nlohmann::json& a = j["axes"][i];
        const std::string axis = "/axes/" + std::to_string(i);
        RotaryAxisSpec s;
        if (!a.is_object()) throw ParseError(places.value(axis), "each axis must be a JSON object", a.dump());
        const std::string letter = readString(a, "letter", std::string(), "an axis's ", places, axis);
        if (letter != "A" && letter != "B" && letter != "C")
            throw ParseError(places.value(a.contains("letter") ? axis + "/letter" : axis),
                             "each axis needs \"letter\": \"A\", \"B\" or \"C\"", a.dump());
        s.letter = letter[0];
        if (m.has(s.letter))
            throw ParseError(places.value(axis + "/letter"), "rotary axis " + letter + " is described twice");
        onlyKnownKeys(a, {"letter", "on", "direction", "pivot"}, "axis " + letter + ": ", places, axis);
        const std::string on = readString(a, "on", "table", "axis " + letter + ": ", places, axis);
        if (on != "table" && on != "head")
            throw ParseError(places.value(axis + "/on"),
                             "axis " + letter + ": \"on\" must be \"table\" or \"head\"", on);
        s.onTable = on == "table";
        if (!a.contains("direction")) throw ParseError(places.value(axis), "axis " + letter + " needs a \"direction\"");
        const Vec3 d = readVector(a["direction"], "axis " + letter + "'s direction", places, axis + "/direction");
        if (glm::length(d) <= tol::kLength)
            throw ParseError(places.value(axis + "/direction"), "axis " + letter + "'s direction is zero");
        // Scaled by its largest component first: the length of (1e300, 0, 0) overflows.
        s.direction = glm::normalize(d / std::max({std::abs(d.x), std::abs(d.y), std::abs(d.z)}));
        if (a.contains("pivot"))
            s.pivot = readVector(a["pivot"], "axis " + letter + "'s pivot", places, axis + "/pivot");
        // A pivot far out rounds away the positions it turns (1e300 - x is 1e300).
        if (std::max({std::abs(s.pivot.x), std::abs(s.pivot.y), std::abs(s.pivot.z)}) > kMaxPivotMm)
            throw ParseError(places.value(axis + "/pivot"),
                             "axis " + letter + "'s pivot lies beyond the 1e9 mm a machine may reach",
                             a["pivot"].dump());
        m.axes.push_back(s);
    }
    return m;
}

Machine loadMachine(const std::string& nameOrFile,
                    const std::function<std::optional<std::string>(const std::string&)>& read) {
    Machine m = builtin(nameOrFile);
    if (!m.name.empty()) return m;
    const auto missing = [&] {
        std::string names;
        for (const std::string& n : builtinMachineNames()) names += (names.empty() ? "" : ", ") + n;
        return Error("--machine '" + nameOrFile + "': no built-in machine of that name (" + names +
                     ") and no file to read");
    };
    if (read) {
        const std::optional<std::string> text = read(nameOrFile);
        if (!text) throw missing();
        return parseMachine(*text, nameOrFile);
    }
    std::error_code ec;
    if (std::filesystem::is_directory(nameOrFile, ec))
        throw Error("--machine '" + nameOrFile + "': a folder, not a machine description file");
    std::ifstream in(nameOrFile, std::ios::binary);
    if (!in) throw missing();
    std::ostringstream text;
    text << in.rdbuf();
    return parseMachine(text.str(), nameOrFile);
}

}  // namespace dexelmill
