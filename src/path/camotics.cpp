/// @file camotics.cpp
/// @brief CAMotics project files. The format is CAMotics' JSON project (tools, workpiece, files,
/// resolution); shapes and units follow CAMotics' tool table: lengths in the tool's units, the
/// cone of a conical tool reaching the full diameter at the tool length.
#include "dexelmill/path/camotics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "dexelmill/io/json_text.h"

#include "dexelmill/error.h"
#include "dexelmill/tool/builders.h"
#include "path/detail/text.h"
#include "path/gcode/texts.h"

namespace dexelmill {

namespace {

constexpr double kInch = 25.4;

using Json = nlohmann::json;

/// The number `key` of object j (at `pointer`), or `fallback` when j has none; a `required` one
/// missing is an error at j.
double number(const Json& j, const char* key, const std::string& where, const JsonPlaces& places,
              const std::string& pointer, double fallback, bool required = false) {
    if (!j.contains(key)) {
        if (required) throw ParseError(places.value(pointer), where + ": missing \"" + key + "\"");
        return fallback;
    }
    const Json& v = j.at(key);
    const SourceLocation at = places.value(pointer + "/" + key);
    if (!v.is_number()) throw ParseError(at, where + ": \"" + key + "\" must be a number", v.dump());
    const double d = v.get<double>();
    if (!std::isfinite(d)) throw ParseError(at, where + ": \"" + key + "\" is not finite", v.dump());
    return d;
}

Diagnostic warning(SourceLocation where, std::string message) {
    Diagnostic d;
    d.severity = Diagnostic::Severity::Warning;
    d.where = std::move(where);
    d.message = std::move(message);
    return d;
}

/// The string `key` of object j (at `pointer`), or `fallback` when j has none.
std::string text(const Json& j, const char* key, const std::string& where, const JsonPlaces& places,
                 const std::string& pointer, const std::string& fallback) {
    if (!j.contains(key)) return fallback;
    const Json& v = j.at(key);
    if (!v.is_string())
        throw ParseError(places.value(pointer + "/" + key), where + ": \"" + key + "\" must be a string", v.dump());
    return v.get<std::string>();
}

/// The boolean `key` of object j (at `pointer`), or `fallback` when j has none.
bool boolean(const Json& j, const char* key, const std::string& where, const JsonPlaces& places,
             const std::string& pointer, bool fallback) {
    if (!j.contains(key)) return fallback;
    const Json& v = j.at(key);
    if (!v.is_boolean())
        throw ParseError(places.value(pointer + "/" + key), where + ": \"" + key + "\" must be true or false",
                         v.dump());
    return v.get<bool>();
}

/// Warns, at the key, of each key of object j (at `pointer`) that is not in `known`: CAMotics reads
/// none of them, and a misspelt one ("snub_diametre", "margn") would otherwise leave its value's
/// default in force unsaid.
/// `what` names the object in the message.
void warnUnknownKeys(const Json& j, std::initializer_list<const char*> known, const std::string& what,
                     const JsonPlaces& places, const std::string& pointer, std::vector<Diagnostic>& diags) {
    for (const auto& item : j.items()) {
        // A named string, not a structured binding: C++17 lets no lambda capture one (clang
        // refuses it).
        const std::string& key = item.key();
        if (std::none_of(known.begin(), known.end(), [&](const char* k) { return key == k; }))
            diags.push_back(warning(places.key(pointer + "/" + jsonPointerToken(key)),
                                    what + " entry \"" + key + "\" ignored"));
    }
}

/// CAMotics reads its enumerations' names in any case of letters.
std::string lower(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

/// The units a tool's or the project's "units" names (j at `pointer`): true for metric.
bool metricUnits(const Json& j, const std::string& where, const JsonPlaces& places, const std::string& pointer) {
    const std::string units = lower(text(j, "units", where, places, pointer, "metric"));
    if (units != "metric" && units != "imperial")
        throw ParseError(places.value(pointer + "/units"), where + ": units must be \"metric\" or \"imperial\"",
                         units);
    return units == "metric";
}

ResolutionMode resolutionMode(const Json& j, const JsonPlaces& places) {
    std::string mode = lower(text(j, "resolution-mode", "project", places, "", "medium"));
    for (char& c : mode)
        if (c == ' ' || c == '-') c = '_';
    if (mode == "manual") return ResolutionMode::Manual;
    if (mode == "low") return ResolutionMode::Low;
    if (mode == "medium") return ResolutionMode::Medium;
    if (mode == "high") return ResolutionMode::High;
    if (mode == "very_high") return ResolutionMode::VeryHigh;
    throw ParseError(places.value("/resolution-mode"),
                     "project: \"resolution-mode\" must be manual, low, medium, high or very_high",
                     j.at("resolution-mode").dump());
}

/// The tool CAMotics makes of `t` (at `pointer`); none for a shape dexelmill has no cutter for,
/// which a warning in `diags` names.
std::optional<Tool> camoticsTool(const Json& t, const std::string& where, const JsonPlaces& places,
                                 const std::string& pointer, std::vector<Diagnostic>& diags) {
    if (!t.is_object()) throw ParseError(places.value(pointer), where + ": a tool must be an object", t.dump());
    // "number" is CAMotics' too: the project's reader numbers the tool by it.
    warnUnknownKeys(t, {"units", "shape", "length", "diameter", "snub_diameter", "description", "number"}, where,
                    places, pointer, diags);
    const double s = metricUnits(t, where, places, pointer) ? 1.0 : kInch;
    std::string shape = lower(text(t, "shape", where, places, pointer, "cylindrical"));
    // CAMotics' other names for two of its shapes.
    if (shape == "cylinder") shape = "cylindrical";
    if (shape == "cone") shape = "conical";
    // Where the shape is (or would be) given: the tool itself when it names none.
    const SourceLocation shapeAt = places.value(t.contains("shape") ? pointer + "/shape" : pointer);
    const double d = number(t, "diameter", where, places, pointer, 0.0, true) * s;
    const double length = number(t, "length", where, places, pointer, 0.0, true) * s;
    if (!(d > 0) || !(length > 0))
        throw ParseError(places.value(pointer + (d > 0 ? "/length" : "/diameter")),
                         where + ": diameter and length must be positive", t.dump());
    ToolLengths lengths{length, 0.0};
    try {
        if (shape == "snubnose") {
            // CAMotics sweeps a cone from the snub at the tip to the diameter at the tool's length:
            // a snub as wide as the tool is a cylinder, and none (or none given) a point.
            const double snub = number(t, "snub_diameter", where, places, pointer, 0.0) * s;
            if (!(snub >= 0) || snub > d)
                throw ParseError(places.value(pointer + "/snub_diameter"),
                                 where + ": snub_diameter must be in [0, diameter]", t.dump());
            if (snub == d) shape = "cylindrical";
            else if (snub == 0.0) shape = "conical";
            else return taperEndMill(snub, std::atan2((d - snub) / 2, length), lengths);
        }
        if (shape == "cylindrical") return flatEndMill(d, lengths);
        if (shape == "ballnose") return ballEndMill(d, lengths);
        if (shape == "conical") {
            // CAMotics: a cone from the point to the full diameter at the tool's length.
            return chamferMill(0.0, std::atan2(d / 2, length), d, lengths);
        }
    } catch (const ParseError&) {
        throw;
    } catch (const Error& e) {
        throw ParseError(places.value(pointer), where + ": no real tool: " + e.what(), t.dump());
    }
    if (shape == "spheroid" || shape == "sphere") {
        diags.push_back(warning(shapeAt, where + ": CAMotics' spheroid tool (an ellipse turned about the axis) "
                                                 "is not supported, as dexelmill's cutters are made of straight "
                                                 "and circular-arc profiles: the project leaves this number "
                                                 "undefined, for a --tool N=SPEC"));
        return std::nullopt;
    }
    throw ParseError(shapeAt,
                     where + ": unknown tool shape (CAMotics' are cylindrical, ballnose, conical, snubnose "
                             "and spheroid)",
                     shape);
}

/// The extension of a path's last component, without its dot and in lower case ("" for none).
std::string extensionOf(const std::string& path) {
    const auto dot = path.find_last_of('.');
    const auto slash = path.find_last_of('/');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
    return lower(path.substr(dot + 1));
}

/// Refuses a file whose name says it holds a solid (a mesh or a level set): read as G-code, it
/// failed at a word of its header ("olid" of an ASCII STL's "solid"), which did not say what it is.
void refuseSolid(const std::string& path) {
    const std::string ext = extensionOf(path);
    std::string kind;
    if (ext == "stl") kind = "an STL mesh";
    else if (ext == "obj") kind = "an OBJ mesh";
    else if (ext == "ply") kind = "a PLY mesh";
    else if (ext == "vdb") kind = "an OpenVDB level set";
    else return;
    throw Error("'" + path + "' is " + kind + ", not a program: a program is G-code, an APT CL file or a CAMotics "
                "project; a solid is given with --stock or --design (.stl or .vdb)");
}

/// The three numbers of j, the value at `pointer`.
Vec3 vec3(const Json& j, const std::string& where, const JsonPlaces& places, const std::string& pointer) {
    if (!j.is_array() || j.size() != 3 || !j[0].is_number() || !j[1].is_number() || !j[2].is_number())
        throw ParseError(places.value(pointer), where + " must be an array of 3 numbers", j.dump());
    return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

}  // namespace

double projectResolution(ResolutionMode mode, const Box& workpiece) {
    double cells = 0.0;
    switch (mode) {
    case ResolutionMode::Low: cells = 1e5; break;
    case ResolutionMode::Medium: cells = 2.5e5; break;
    case ResolutionMode::High: cells = 5e6; break;
    case ResolutionMode::VeryHigh: cells = 1e7; break;
    case ResolutionMode::Manual: throw Error("projectResolution: the manual mode keeps the project's own number");
    }
    const Vec3 size = workpiece.size();
    return std::cbrt(size.x * size.y * size.z / cells);
}

Project parseCamoticsProject(std::string_view text, const std::string& fileName,
                             const std::string& directory) {
    if (const std::optional<JsonTextFault> fault = jsonTextFault(text, /*comments=*/true))
        throw ParseError(locateByte(text, fault->byte, fileName), "CAMotics project: " + fault->message);
    Json j;
    try {
        j = Json::parse(text.begin(), text.end(), nullptr, true, /*ignore_comments=*/true);
    } catch (const Json::parse_error& e) {
        const SourceLocation loc = locateByte(text, e.byte > 0 ? e.byte - 1 : 0, fileName);
        const std::size_t at = std::min(text.size(), e.byte > 0 ? e.byte - 1 : 0);
        throw ParseError(loc, "invalid JSON in CAMotics project", std::string(text.substr(at, 20)));
    } catch (const Json::exception& e) {
        // Valid syntax the library still refuses; a number beyond double's range is found above.
        throw ParseError({fileName, 0, 0}, std::string("unreadable JSON in CAMotics project: ") + e.what());
    }
    const JsonPlaces places(text, fileName, true);
    if (!j.is_object()) throw ParseError(places.value(""), "a CAMotics project must be a JSON object");
    Project p;
    p.file = fileName;
    try {
        p.metric = metricUnits(j, "project", places, "");
        if (!p.metric)
            p.diagnostics.push_back(warning(
                places.value("/units"), "project units are imperial: as in CAMotics, they only choose how lengths "
                                        "are shown; the workpiece and resolution are in mm, and G-code starts in mm "
                                        "until it says G20"));
        p.resolutionMode = resolutionMode(j, places);
        p.resolution = number(j, "resolution", "project", places, "", 0.0);
        if (j.contains("resolution") && !(p.resolution > 0)) {
            p.unusableResolution = p.resolution;
            p.resolution = 0.0;
        }
        if (j.contains("tools")) {
            const Json& tools = j.at("tools");
            if (!tools.is_object())
                throw ParseError(places.value("/tools"), "\"tools\" must be an object", tools.dump().substr(0, 40));
            // CAMotics numbers a tool by its "number", by its key where it has none, and of two
            // tools with one number keeps the later in the file.
            struct Defined {
                int number = 0;
                SourceLocation at;  ///< its key's place
                std::string key;
                std::optional<Tool> tool;
            };
            std::vector<Defined> defined;
            for (const auto& [key, t] : tools.items()) {
                const std::string pointer = "/tools/" + jsonPointerToken(key);
                int n = 0;
                try {
                    std::size_t used = 0;
                    n = std::stoi(key, &used);
                    if (used != key.size() || n < 0) throw std::invalid_argument(key);
                } catch (const std::exception&) {
                    throw ParseError(places.key(pointer), "tool numbers must be integers", key);
                }
                std::optional<Tool> tool = camoticsTool(t, "tool " + key, places, pointer, p.diagnostics);
                if (t.contains("number")) {
                    const Json& v = t.at("number");
                    const double number = v.is_number() ? v.get<double>() : -1.0;
                    if (!(number >= 0.0 && number <= double(std::numeric_limits<int>::max()) &&
                          number == std::floor(number)))
                        throw ParseError(places.value(pointer + "/number"),
                                         "tool " + key + ": \"number\" must be a whole number from 0", v.dump());
                    if (int(number) != n) {
                        Diagnostic d = warning(places.value(pointer + "/number"),
                                               "tool " + key + " is tool " + std::to_string(int(number)) +
                                                   ": CAMotics numbers a project's tool by its \"number\", not by "
                                                   "its key");
                        d.severity = Diagnostic::Severity::Note;
                        p.diagnostics.push_back(std::move(d));
                        n = int(number);
                    }
                }
                defined.push_back({n, places.key(pointer), key, std::move(tool)});
            }
            std::stable_sort(defined.begin(), defined.end(), [](const Defined& x, const Defined& y) {
                return std::pair(x.at.line, x.at.column) < std::pair(y.at.line, y.at.column);
            });
            std::map<int, const Defined*> first;
            for (const Defined& d : defined) {
                const auto [earlier, fresh] = first.emplace(d.number, &d);
                if (!fresh) {
                    p.diagnostics.push_back(warning(
                        earlier->second->at, "tool " + earlier->second->key + " (tool " + std::to_string(d.number) +
                                                 ") is replaced by tool " + d.key + " at line " +
                                                 std::to_string(d.at.line) +
                                                 ", which has its number: CAMotics keeps the later"));
                    earlier->second = &d;
                }
                if (d.tool) p.tools.insert_or_assign(d.number, *d.tool);
                else p.tools.erase(d.number);
            }
        }
        if (j.contains("workpiece")) {
            const Json& w = j.at("workpiece");
            if (!w.is_object())
                throw ParseError(places.value("/workpiece"), "\"workpiece\" must be an object",
                                 w.dump().substr(0, 40));
            warnUnknownKeys(w, {"automatic", "margin", "bounds"}, "workpiece", places, "/workpiece", p.diagnostics);
            p.workpiece.automatic = boolean(w, "automatic", "workpiece", places, "/workpiece", p.workpiece.automatic);
            p.workpiece.marginPercent = number(w, "margin", "workpiece", places, "/workpiece", p.workpiece.marginPercent);
            if (w.contains("bounds")) {
                const Json& b = w.at("bounds");
                if (!b.is_object() || !b.contains("min") || !b.contains("max"))
                    throw ParseError(places.value("/workpiece/bounds"), "workpiece bounds need min and max",
                                     b.dump().substr(0, 40));
                warnUnknownKeys(b, {"min", "max"}, "workpiece bounds", places, "/workpiece/bounds", p.diagnostics);
                p.workpiece.bounds.lo = vec3(b.at("min"), "workpiece bounds min", places, "/workpiece/bounds/min");
                p.workpiece.bounds.hi = vec3(b.at("max"), "workpiece bounds max", places, "/workpiece/bounds/max");
                if (!p.workpiece.automatic && p.workpiece.bounds.isEmpty())
                    throw ParseError(places.value("/workpiece/bounds"), "workpiece bounds are empty (min > max)",
                                     b.dump().substr(0, 60));
            }
        }
        if (j.contains("files")) {
            const Json& files = j.at("files");
            if (!files.is_array())
                throw ParseError(places.value("/files"), "\"files\" must be an array", files.dump().substr(0, 40));
            for (std::size_t i = 0; i < files.size(); ++i) {
                const Json& f = files.at(i);
                const std::string pointer = "/files/" + std::to_string(i);
                if (f.is_string())
                    p.files.push_back({detail::joinPath(directory, f.get<std::string>()), places.value(pointer)});
                else if (f.is_object() && f.contains("path") && f.at("path").is_string()) {
                    warnUnknownKeys(f, {"path"}, "program " + std::to_string(i + 1), places, pointer, p.diagnostics);
                    p.files.push_back({detail::joinPath(directory, f.at("path").get<std::string>()),
                                       places.value(pointer + "/path")});
                }
                else
                    throw ParseError(places.value(pointer), "a file entry must be a string", f.dump().substr(0, 40));
            }
        }
        static const std::set<std::string> known = {"units", "resolution", "resolution-mode", "tools", "workpiece", "files"};
        for (const auto& [key, v] : j.items()) {
            (void)v;
            if (!known.count(key))
                p.diagnostics.push_back(
                    warning(places.key("/" + jsonPointerToken(key)), "project entry \"" + key + "\" ignored"));
        }
    } catch (const Json::exception& e) {
        throw ParseError({fileName, 0, 0}, std::string("CAMotics project field of the wrong type: ") + e.what());
    }
    return p;
}

Project readCamoticsProject(const std::string& path, const FileSource& files) {
    return parseCamoticsProject(detail::readFile(files, path), path, detail::directoryOf(path));
}

Program runProject(const Project& project, const GcodeOptions& options) {
    GcodeOptions o = options;
    o.toolChangeOnT = true;
    // Each program is read once: the text read to tell its kind goes on to its reader.
    std::vector<detail::gcode::NamedText> gcodeFiles;
    Program program;
    // Runs of G-code files share one machine; an APT file stands alone.
    auto flush = [&]() {
        if (gcodeFiles.empty()) return;
        Program part = detail::gcode::runTexts(std::move(gcodeFiles), o);
        gcodeFiles.clear();
        program.append(std::move(part));
    };
    for (const ProjectFile& file : project.files) {
        const std::string& f = file.path;
        std::string text;
        try {
            refuseSolid(f);
            text = detail::readFile(o.files, f);
        } catch (const Error& e) {
            // A program the project names, missing or no program: said at its entry.
            if (file.entry.line > 0) throw ParseError(file.entry, e.what());
            throw;
        }
        if (detectProgramKind(f, text) == ProgramKind::Apt) {
            flush();
            AptOptions a;
            a.chordTolerance = o.chordTolerance;
            a.initialInches = o.initialInches;
            a.maxMoves = o.maxMoves - std::min(o.maxMoves, program.path.moves.size());
            a.maxMovesReason = o.maxMovesReason;
            program.append(parseApt(text, f, a));
        } else {
            gcodeFiles.push_back({f, std::move(text)});
        }
    }
    flush();
    for (const auto& [n, t] : project.tools) program.tools.insert_or_assign(n, t);
    program.diagnostics.insert(program.diagnostics.begin(), project.diagnostics.begin(), project.diagnostics.end());
    std::set<int> warned;
    for (const ToolChange& tc : program.path.toolChanges) {
        if (tc.tool == 0 || program.tools.count(tc.tool) || warned.count(tc.tool)) continue;
        warned.insert(tc.tool);
        program.diagnostics.push_back(warning(program.path.where(tc.source),
                                              "the program calls tool " + std::to_string(tc.tool) +
                                                  ", which the project does not define"));
    }
    return program;
}

Box automaticWorkpieceBounds(const Program& program, double marginPercent) {
    return automaticWorkpieceBounds(program.path, program.tools, marginPercent);
}

Box automaticWorkpieceBounds(const ToolPath& path, const ToolTable& tools, double marginPercent) {
    Box box = cuttingBounds(path, tools);
    if (box.isEmpty()) return box;
    // CAMotics starts the block at z = 0, and makes it kMinAutomaticThickness thicker where it
    // would be thinner than that. Cuts wholly above z = 0 leave a block of that thickness below it.
    box.hi.z = 0.0;
    if (box.hi.z - box.lo.z < kMinAutomaticThickness) box.lo.z = std::min(box.lo.z, 0.0) - kMinAutomaticThickness;
    const Vec3 size = box.size();
    const Vec3 margin = size * (marginPercent / 100.0);
    box.lo -= margin;
    box.hi.x += margin.x;
    box.hi.y += margin.y;
    return box;
}

Box cuttingBounds(const ToolPath& path, const ToolTable& tools) {
    Box box;
    // A tool the program calls but nobody defined counts as the widest defined tool.
    double widest = 0.0;
    for (const auto& [n, t] : tools) widest = std::max(widest, t.cuttingRadius());
    for (const Move& m : path.moves) {
        if (m.rapid) continue;
        double radius = widest;
        auto it = tools.find(m.tool);
        if (it != tools.end()) radius = it->second.cuttingRadius();
        // The tip's path, curved where a machine carries it, and the axis at each of its poses.
        // Between poses the tip strays at most the path's sag, and the axis turns at most its
        // axisStep, which moves the rim across by at most radius times that (|a x e_k| is
        // 1-Lipschitz in a).
        const TipPath path = tipPath(m);
        const double pad = path.sag + radius * path.axisStep;
        for (const ToolPose& pose : path.poses) {
            // Widen across the axis: for a vertical axis, in x and y.
            const Vec3 a = glm::normalize(pose.axis);
            for (int k = 0; k < 3; ++k) {
                const double across = radius * std::sqrt(std::max(0.0, 1.0 - a[k] * a[k])) + pad;
                Vec3 lo = pose.tip, hi = pose.tip;
                lo[k] -= across;
                hi[k] += across;
                box.expand(lo);
                box.expand(hi);
            }
        }
    }
    return box;
}

ProgramKind detectProgramKind(const std::string& path, std::string_view text) {
    const std::string ext = extensionOf(path);
    if (ext == "camotics") return ProgramKind::Camotics;
    if (ext == "apt" || ext == "cl" || ext == "cls" || ext == "aptsource") return ProgramKind::Apt;
    static const std::set<std::string> gcode = {"nc", "ngc", "gcode", "gc", "tap", "cnc", "g", "txt", "eia", "mpf", "iso"};
    if (gcode.count(ext)) return ProgramKind::Gcode;
    // By content: the first statement of an APT file is MAJOR/... or a $$ comment.
    std::size_t i = 0;
    while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    if (i < text.size() && text[i] == '{') return ProgramKind::Camotics;
    if (text.substr(i, 2) == "$$") return ProgramKind::Apt;
    std::size_t k = i;
    while (k < text.size() && (std::isalpha(static_cast<unsigned char>(text[k])) || text[k] == '_')) ++k;
    if (k - i >= 3 && k < text.size() && text[k] == '/') return ProgramKind::Apt;
    return ProgramKind::Gcode;
}

Program readProgram(const std::string& path, const GcodeOptions& gcode, const AptOptions& apt) {
    refuseSolid(path);
    const std::string text = detail::readFile(gcode.files, path);
    switch (detectProgramKind(path, text)) {
    case ProgramKind::Camotics: {
        const Project project = parseCamoticsProject(text, path, detail::directoryOf(path));
        return runProject(project, gcode);
    }
    case ProgramKind::Apt: {
        Program p = parseApt(text, path, apt);
        // An APT CL file gives the tool axis in the part frame itself: a machine has nothing to do.
        if (gcode.machine) {
            Diagnostic d;
            d.where = SourceLocation{path, 0, 0};
            d.message = "--machine " + gcode.machine->name +
                        " is not used: an APT CL file gives the tool axis in the part frame (GOTO's i,j,k)";
            p.diagnostics.insert(p.diagnostics.begin(), d);
        }
        if (gcode.startPosition) {
            Diagnostic d;
            d.where = SourceLocation{path, 0, 0};
            d.message = "--start is not used: an APT CL file places the tool itself (FROM, or its first GOTO)";
            p.diagnostics.insert(p.diagnostics.begin(), d);
        }
        return p;
    }
    case ProgramKind::Gcode:
    default: {
        Program p = parseGcode(text, path, gcode);
        return p;
    }
    }
}

}  // namespace dexelmill
