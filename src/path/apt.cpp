/// @file apt.cpp
/// @brief APT CL reader. Statement forms follow the APT language (ANSI X3.37) as written by
/// SolidWorks CAM / CAMWorks and NX postprocessor input: `MAJOR/arg, arg, ...`, `$` continues a
/// statement on the next line, `$$` starts a comment.
#include "dexelmill/path/apt.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>
#include <optional>
#include <sstream>

#include "dexelmill/decimal.h"
#include "dexelmill/error.h"
#include "dexelmill/path/motion.h"
#include "dexelmill/tool/builders.h"
#include "path/detail/arc.h"
#include "path/detail/diagnostics.h"
#include "path/detail/text.h"

namespace dexelmill {

namespace {

using detail::upper;

constexpr double kInch = 25.4;
constexpr double kPi = 3.14159265358979323846;
/// CIRCLE: the radius to the end may differ from the radius to the start by this much (mm) and
/// this fraction before the arc is rejected.
constexpr double kArcRadiusAbsTol = 0.02;
constexpr double kArcRadiusRelTol = 0.001;
/// Peck drilling: the rapid back into the hole stops this far above the previous depth (mm).
constexpr double kPeckClearance = 0.254;
/// An i,j,k vector printed with about 6 significant digits has a length within a few 1e-6 of 1;
/// one further off than this was not meant as a unit vector, and its normalisation is reported.
constexpr double kUnitVectorRounding = 1e-5;
/// The largest tool number LOAD/TOOL takes: the entries the reader makes are numbered after the
/// program's, and stay far below INT_MAX.
constexpr double kMaxToolNumber = 1e7;
/// A FROM within this distance (mm) of where the tool is only states its place again.
constexpr double kRestatedPositionMm = 1e-6;
/// CUTTER/d,r,e,f,alpha,beta,h: APT's full form; CUTTER/d and CUTTER/d,r are its short ones.
constexpr std::array<const char*, 7> kCutterNames = {"d", "r", "e", "f", "alpha", "beta", "h"};

struct Token {
    std::string text;  ///< upper case, trimmed
    int line = 0;
    int col = 0;
};

struct Statement {
    std::string major;
    std::vector<Token> args;
    int line = 0;
    int col = 0;
    bool hasSlash = false;
    std::string raw;  ///< for messages
};

struct CutterSpec {
    std::vector<double> params;  ///< mm (angles in degrees)
    double unit = 1.0;           ///< the length unit the values were printed in (mm)
    double cuttingLength = 0.0;
    SourceLocation where;  ///< the CUTTER statement, which every note and error about its values names
    /// The statement that gave the tool this description: the CUTTER, or a CSI_SET_FLUTE_LENGTH
    /// that changed its cutting length.
    SourceLocation describedAt;
    bool cut = false;  ///< some move was made with it

    /// Whether `later` states this tool again: the same numbers, and the same cutting length
    /// where it gives one.
    bool restatedBy(const CutterSpec& later) const {
        return params == later.params && (later.cuttingLength == 0.0 || later.cuttingLength == cuttingLength);
    }
};

class AptReader {
public:
    AptReader(const AptOptions& opt, std::string fileName, Program& out)
        : opt_(opt), file_(std::move(fileName)), out_(out) {
        scale_ = opt.initialInches ? kInch : 1.0;
        if (!(opt.chordTolerance > 0.0)) throw Error("AptOptions::chordTolerance must be positive");
        out_.path.files.push_back(file_);
    }

    void run(std::string_view text) {
        std::vector<Statement> statements = split(text);
        for (const Statement& s : statements) {
            cur_ = &s;
            if (finished_) {
                diags_.warn(loc(s), "statement after FINI ignored", "after FINI");
                continue;
            }
            execute(s);
        }
        if (circle_)
            throw ParseError(circleWhere_, "CIRCLE without the GOTO that ends it (truncated file?)");
        numberNewTools();
        buildTools();
        diags_.appendTo(out_.diagnostics);
    }

private:
    SourceLocation loc(const Statement& s, int col = 0) const {
        return {file_, s.line, col ? col : s.col};
    }
    SourceLocation loc(const Token& t) const { return {file_, t.line, t.col}; }
    [[noreturn]] void fail(const Statement& s, const std::string& msg) const {
        throw ParseError(loc(s), msg, s.raw.substr(0, 60));
    }
    [[noreturn]] void fail(const Token& t, const std::string& msg) const {
        throw ParseError(loc(t), msg, t.text);
    }

    // ---- lexing ----
    std::vector<Statement> split(std::string_view text) {
        std::vector<Statement> out;
        std::size_t pos = 0;
        int lineNo = 0;
        Statement st;
        bool continuing = false;
        int dollarCol = 0;  // of the last line's continuing '$'
        while (pos < text.size()) {
            std::size_t e = text.find('\n', pos);
            if (e == std::string_view::npos) e = text.size();
            std::string_view line = text.substr(pos, e - pos);
            pos = e + 1;
            ++lineNo;
            if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
            // Comments.
            const std::size_t cm = line.find("$$");
            bool cont = false;
            if (cm != std::string_view::npos) line = line.substr(0, cm);
            std::size_t end = line.size();
            while (end > 0 && (line[end - 1] == ' ' || line[end - 1] == '\t')) --end;
            // A text statement's text is literal: a '$' that ends it is text, not a continuation.
            if (end > 0 && line[end - 1] == '$' && (continuing || textStart(line) == std::string_view::npos)) {
                cont = true;
                dollarCol = int(end);
                --end;
            }
            line = line.substr(0, end);
            if (!continuing) {
                std::size_t i = 0;
                while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
                if (i >= line.size()) {
                    if (cont) {  // a lone '$'
                        st = Statement{};
                        st.line = lineNo;
                        st.col = int(i) + 1;
                        continuing = true;
                    }
                    continue;
                }
                st = Statement{};
                st.line = lineNo;
                st.col = int(i) + 1;
                parseHead(st, line, i, lineNo);
            } else {
                parseArgs(st, line, 0, lineNo);
            }
            continuing = cont;
            if (!continuing) out.push_back(std::move(st));
        }
        if (continuing)
            throw ParseError({file_, lineNo, dollarCol},
                             "statement continued with '$' at the end of the file (truncated file?)",
                             st.raw.substr(0, 60));
        return out;
    }

    /// The major word of a statement whose line starts with `head`: without blanks, upper case.
    static std::string majorWord(std::string_view head) {
        std::string major;
        for (char c : head)
            if (c != ' ' && c != '\t') major += upper(c);
        return major;
    }
    /// Statements whose argument is the rest of their line, as text.
    static bool isTextMajor(const std::string& major) {
        return major == "PARTNO" || major == "INSERT" || major == "PPRINT" || major == "REMARK";
    }
    /// Where the text begins when a line starts a text statement, in either of APT's forms,
    /// `PARTNO text` or `PARTNO/text`; npos for any other statement.
    static std::size_t textStart(std::string_view line) {
        std::size_t i = 0;
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        const std::size_t slash = line.find('/', i);
        if (slash != std::string_view::npos && isTextMajor(majorWord(line.substr(i, slash - i)))) return slash + 1;
        std::size_t e = i;
        while (e < line.size() && std::isalpha(static_cast<unsigned char>(line[e]))) ++e;
        if (e < line.size() && (line[e] == ' ' || line[e] == '\t') && isTextMajor(majorWord(line.substr(i, e - i))))
            return e + 1;
        return std::string_view::npos;
    }

    void parseHead(Statement& st, std::string_view line, std::size_t i, int lineNo) {
        st.raw = std::string(line.substr(i));
        // Text statements keep their text as one argument; they never continue (split).
        if (const std::size_t text = textStart(line); text != std::string_view::npos) {
            st.major = majorWord(line.substr(i, text - 1 - i));
            st.hasSlash = line[text - 1] == '/';
            st.args.push_back({std::string(line.substr(text)), lineNo, int(text) + 1});
            return;
        }
        const std::size_t slash = line.find('/', i);
        st.major = majorWord(line.substr(i, slash == std::string_view::npos ? std::string_view::npos : slash - i));
        if (slash == std::string_view::npos) return;
        st.hasSlash = true;
        parseArgs(st, line, slash + 1, lineNo);
    }

    void parseArgs(Statement& st, std::string_view line, std::size_t i, int lineNo) {
        while (i <= line.size()) {
            std::size_t e = line.find(',', i);
            if (e == std::string_view::npos) e = line.size();
            std::size_t b = i;
            while (b < e && (line[b] == ' ' || line[b] == '\t')) ++b;
            std::size_t t = e;
            while (t > b && (line[t - 1] == ' ' || line[t - 1] == '\t')) --t;
            if (b < t || e < line.size()) {
                Token tok;
                for (std::size_t k = b; k < t; ++k) tok.text += upper(line[k]);
                tok.line = lineNo;
                tok.col = int(b) + 1;
                st.args.push_back(tok);
            }
            if (e == line.size()) break;
            i = e + 1;
        }
    }

    static bool isNumber(const std::string& s) {
        if (s.empty()) return false;
        bool digit = false;
        for (std::size_t k = 0; k < s.size(); ++k) {
            const char c = s[k];
            if (c >= '0' && c <= '9') digit = true;
            else if (c == '.' || ((c == '-' || c == '+') && (k == 0 || s[k - 1] == 'E'))) continue;
            else if (c == 'E' && digit) continue;
            else return false;
        }
        return digit;
    }
    double number(const Token& t) const {
        if (!isNumber(t.text)) fail(t, "bad number");
        char* end = nullptr;
        const double v = std::strtod(t.text.c_str(), &end);
        if (end != t.text.c_str() + t.text.size() || !std::isfinite(v)) fail(t, "bad number");
        return v;
    }
    std::vector<double> numbers(const Statement& s, std::size_t from = 0) const {
        std::vector<double> v;
        for (std::size_t k = from; k < s.args.size(); ++k) v.push_back(number(s.args[k]));
        return v;
    }

    // ---- statements ----
    void execute(const Statement& s) {
        const std::string& w = s.major;
        if (w == "GOTO") return gotoPoint(s);
        if (w == "FEDRAT") return warnKind(s, "feed rate FEDRAT is not simulated (ignored)");
        if (w == "RAPID") {
            rapidNext_ = true;
            return ignoreArgs(s, 0, "RAPID");
        }
        if (w == "CIRCLE") return circle(s);
        if (w == "FROM") return from(s);
        if (w == "GODLTA") return godlta(s);
        if (w == "CUTTER") return cutter(s);
        if (w == "LOAD" || w == "TOOLNO" || w == "LOADTL") return loadTool(s);
        if (w == "UNITS" || w == "UNIT") return units(s);
        if (w == "CSYS") return csys(s);
        if (w == "TRNTYP") {
            world_ = !s.args.empty() && s.args[0].text == "WORLD";
            if (!world_) diags_.warn(loc(s), "TRNTYP other than WORLD: CSYS maps local coordinates to the part frame", "TRNTYP");
            return;
        }
        if (w == "MULTAX") return multax(s);
        if (w == "CYCLE") return cycle(s);
        if (w == "CUTCOM") {
            if (!s.args.empty() && s.args[0].text != "OFF")
                diags_.warn(loc(s), "cutter compensation CUTCOM is not simulated: the path is the CL path", "CUTCOM");
            return;
        }
        if (w == "SPINDL") return warnKind(s, "spindle SPINDL is not simulated (ignored)");
        if (w == "COOLNT") return warnKind(s, "coolant COOLNT is not simulated (ignored)");
        if (w == "CSI_SET_FLUTE_LENGTH") return fluteLength(s);
        if (w == "FINI") {
            finished_ = true;
            return ignoreArgs(s, 0, "FINI");
        }
        if (w == "INSERT" && statedStock(s)) return;
        if (w == "PARTNO" || w == "INSERT" || w == "PPRINT" || w == "REMARK")
            return warnKind(s, w + " text ignored");
        if (w == "SELECT") return warnKind(s, "SELECT/TOOL (tool preselection) ignored");
        if (w.empty()) fail(s, "statement without a major word");
        warnKind(s, "statement " + w + " ignored");
    }

    /// CSI_SET_FLUTE_LENGTH/L (CAMWorks): the cutting length of the CUTTER waiting for its
    /// LOAD/TOOL, or else of the tool in the spindle.
    void fluteLength(const Statement& s) {
        const auto v = numbers(s);
        if (v.size() != 1 || !(v[0] > 0)) fail(s, "CSI_SET_FLUTE_LENGTH needs one positive length");
        if (pending_) {
            pending_->cuttingLength = v[0] * scale_;
            return;
        }
        if (!loaded_ || !cutters_.count(key_)) return;
        CutterSpec spec = cutters_.at(key_);
        spec.cuttingLength = v[0] * scale_;
        if (spec.cut) spec.describedAt = loc(s);
        spec.cut = false;
        define(spec, s);
    }

    /// CAMWorks states the stock's size as `INSERT/Stock Size X350. Y150. Z10.5` (in the program's
    /// units, any case and spacing): records it and returns true; other text returns false.
    bool statedStock(const Statement& s) {
        if (s.args.empty()) return false;
        std::string t;
        for (char c : s.args[0].text)
            if (c != ' ' && c != '\t') t += upper(c);
        if (t.rfind("STOCKSIZE", 0) != 0) return false;
        std::size_t i = 9;
        Vec3 size(0.0);
        for (int k = 0; k < 3; ++k) {
            if (i >= t.size() || t[i] != "XYZ"[k]) return false;
            const char* begin = t.c_str() + i + 1;
            char* end = nullptr;
            const double v = std::strtod(begin, &end);
            if (end == begin) return false;
            if (!(v > 0.0) || !std::isfinite(v)) fail(s, "a stated stock size must be positive");
            size[k] = v * scale_;
            i = std::size_t(end - t.c_str());
        }
        if (i != t.size()) return false;
        out_.statedStock = StatedStock{size, loc(s)};
        return true;
    }

    void warnKind(const Statement& s, const std::string& message) {
        diags_.warn(loc(s), message, "apt:" + s.major);
    }

    void units(const Statement& s) {
        if (s.args.empty()) fail(s, "UNITS needs MM or INCHES");
        const std::string& u = s.args[0].text;
        if (u == "MM") scale_ = 1.0;
        else if (u == "INCHES" || u == "INCH" || u == "IN") scale_ = kInch;
        else fail(s.args[0], "unknown units");
        if (s.args.size() > 1) fail(s.args[1], "UNITS takes one word, MM or INCHES");
    }

    /// Warns of the arguments of s from `first` on, which its form does not take.
    void ignoreArgs(const Statement& s, std::size_t first, const std::string& form) {
        for (std::size_t k = first; k < s.args.size(); ++k)
            diags_.warn(loc(s.args[k]), form + " argument " + s.args[k].text + " ignored", "apt args " + form);
    }

    void csys(const Statement& s) {
        const auto v = numbers(s);
        if (v.size() != 12) fail(s, "CSYS needs 12 numbers (a 3x4 matrix)");
        // Rows: r11 r12 r13 t1 / r21 r22 r23 t2 / r31 r32 r33 t3.
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) rot_[c][r] = v[std::size_t(4 * r + c)];
            trans_[r] = v[std::size_t(4 * r + 3)] * scale_;
        }
        for (int c = 0; c < 3; ++c) {
            const double len = glm::length(rot_[c]);
            if (std::abs(len - 1.0) > 1e-3) fail(s, "CSYS rotation is not orthonormal");
        }
        if (std::abs(glm::dot(rot_[0], rot_[1])) > 1e-3 || std::abs(glm::dot(rot_[1], rot_[2])) > 1e-3 ||
            std::abs(glm::dot(rot_[0], rot_[2])) > 1e-3)
            fail(s, "CSYS rotation is not orthonormal");
        haveCsys_ = true;
        axis_ = defaultAxis();
    }

    /// The axis of a GOTO without i,j,k where no MULTAX/ON is in force: the CSYS's z column, or +z.
    Vec3 defaultAxis() const { return haveCsys_ ? glm::normalize(rot_[2]) : Vec3(0, 0, 1); }

    /// MULTAX[/ON] gives GOTO and FROM a tool axis i,j,k after x,y,z; MULTAX/OFF ends that, and
    /// the tool goes back to the default axis (its next move turns there).
    void multax(const Statement& s) {
        const std::string word = s.args.empty() ? "ON" : s.args[0].text;
        if (word == "ON") {
            multax_ = Multax::On;
        } else if (word == "OFF") {
            multax_ = Multax::Off;
            axis_ = defaultAxis();
        } else {
            fail(s.args[0], "MULTAX takes ON or OFF");
        }
        ignoreArgs(s, 1, "MULTAX");
    }

    /// The tool axis of a GOTO or FROM with 6 numbers. Under MULTAX/OFF a CL point is x,y,z alone
    /// (a record's six numbers are two points there), so they are no axis: an error.
    Vec3 toolAxisOf(const Statement& s, const std::vector<double>& v) {
        if (multax_ == Multax::Off)
            fail(s.args[3], s.major + " with 6 numbers under MULTAX/OFF, where a point is x,y,z: a tool axis i,j,k "
                                      "needs MULTAX/ON");
        return axisOf(s, v, 3, "tool axis");
    }

    Vec3 toPart(const Vec3& p) const {
        if (world_ || !haveCsys_) return p;
        return rot_[0] * p.x + rot_[1] * p.y + rot_[2] * p.z + trans_;
    }
    /// The unit vector of the i,j,k in v[first..first+2] (s's numbers), in the part frame; one not
    /// of unit length is normalised with a warning (`what` names it).
    Vec3 axisOf(const Statement& s, const std::vector<double>& v, std::size_t first, const char* what) {
        Vec3 a(v[first], v[first + 1], v[first + 2]);
        // Lengths taken over the largest component, so that (1e300, 0, 0) does not overflow.
        const double big = std::max({std::abs(a.x), std::abs(a.y), std::abs(a.z)});
        if (!(big > 0.0)) fail(s, std::string(what) + " i,j,k of zero length");
        a /= big;
        const double given = big * glm::length(a);
        if (!world_ && haveCsys_) a = rot_[0] * a.x + rot_[1] * a.y + rot_[2] * a.z;
        const double len = glm::length(a);
        if (!(big * len > 1e-9)) fail(s, std::string(what) + " i,j,k of zero length");
        if (std::abs(given - 1.0) > kUnitVectorRounding) {
            std::ostringstream msg;
            msg << what << " i,j,k of length " << given << ", not 1: taken as the unit vector along it";
            diags_.warn(loc(s.args[first]), msg.str(), "apt non-unit vector");
        }
        return a / len;
    }

    void cutter(const Statement& s) {
        const auto v = numbers(s);
        if (v.empty() || v.size() > kCutterNames.size())
            fail(s, "CUTTER needs d, d,r or d,r,e,f,alpha,beta,h (1, 2 or 7 numbers)");
        if (v.size() > 2 && v.size() < kCutterNames.size()) {
            std::string missing;
            for (std::size_t k = v.size(); k < kCutterNames.size(); ++k)
                missing += std::string(missing.empty() ? "" : ",") + kCutterNames[k];
            fail(s, "CUTTER with " + std::to_string(v.size()) +
                        " numbers: APT's forms are d, d,r and d,r,e,f,alpha,beta,h; this one lacks " + missing);
        }
        CutterSpec spec;
        for (std::size_t k = 0; k < v.size(); ++k)
            spec.params.push_back((k == 4 || k == 5) ? v[k] : v[k] * scale_);
        spec.unit = scale_;
        spec.where = loc(s);
        spec.describedAt = spec.where;
        if (!(spec.params[0] > 0)) fail(s.args[0], "CUTTER diameter must be positive");
        if (v.size() >= 2 && !(v[1] >= 0)) fail(s.args[1], "CUTTER corner radius must not be negative");
        if (v.size() == 2 && !roundsTo(v[1], 0.5 * v[0], 1.0) && v[1] > 0.5 * v[0]) {
            const auto [r, halfD] = decimalsApart(v[1], 0.5 * v[0]);
            fail(s.args[1], "CUTTER corner radius " + r + " exceeds half the diameter, " + halfD);
        }
        if (v.size() == 7 && !(v[6] >= 0)) fail(s.args[6], "CUTTER height must not be negative");
        // After LOAD/TOOL, a CUTTER describes the loaded tool; otherwise the LOAD/TOOL that
        // follows claims it, or the next motion takes it (requireTool).
        if (loaded_ && !cutters_.count(key_)) cutters_[key_] = spec;
        else pending_ = spec;
    }

    /// LOAD/TOOL,n, TOOLNO/n and LOADTL/n (the word of the Fusion and NCL posts): load tool n.
    void loadTool(const Statement& s) {
        std::size_t k = 0;
        if (!s.args.empty() && s.args[0].text == "TOOL") k = 1;
        const std::string form = s.major == "LOAD" ? "LOAD/TOOL" : s.major;
        if (k >= s.args.size()) fail(s, form + " needs a tool number");
        const double n = number(s.args[k]);
        if (n < 0 || n != std::floor(n) || n > kMaxToolNumber) fail(s.args[k], "bad tool number");
        tool_ = int(n);
        largestNumber_ = std::max(largestNumber_, tool_);
        const auto known = keyOf_.find(tool_);
        selectKey(known != keyOf_.end() ? known->second : tool_, s);
        keyOf_[tool_] = key_;
        if (pending_) {
            const CutterSpec spec = *pending_;
            pending_.reset();
            define(spec, s);
        }
        ignoreArgs(s, k + 1, form);
    }

    /// Moves from here on are made with the tool-table entry `key`: a tool change unless it is
    /// the one in use. Changes with no move between them are one change.
    void selectKey(int key, const Statement& s) {
        if (loaded_ && key == key_) return;
        loaded_ = true;
        key_ = key;
        auto& changes = out_.path.toolChanges;
        if (!changes.empty() && changes.back().moveIndex == out_.path.moves.size()) changes.pop_back();
        if (!changes.empty() && changes.back().tool == key) return;
        ToolChange tc;
        tc.moveIndex = out_.path.moves.size();
        tc.tool = key;
        tc.source = {0, s.line};
        changes.push_back(tc);
    }

    /// Gives the tool in the spindle the cutter `spec`: in place until a move has been made with
    /// its entry, after that (unless spec only states it again) as a new entry of its own, so
    /// that the moves made before keep the tool they were made with.
    void define(const CutterSpec& spec, const Statement& s) {
        const auto it = cutters_.find(key_);
        if (it == cutters_.end() || !it->second.cut) {
            cutters_[key_] = spec;
            return;
        }
        if (it->second.restatedBy(spec)) return;
        const int key = -int(newTools_.size()) - 1;
        newTools_.push_back({tool_, spec.describedAt, it->second.where.line});
        cutters_[key] = spec;
        keyOf_[tool_] = key;
        selectKey(key, s);
    }

    /// A motion statement: the CUTTER no LOAD/TOOL claimed takes effect here, and there must be
    /// a tool.
    void requireTool(const Statement& s) {
        if (pending_) {
            const CutterSpec spec = *pending_;
            pending_.reset();
            if (!loaded_) {
                diags_.note(spec.where, "CUTTER without LOAD/TOOL: taken as tool 1");
                tool_ = 1;
                largestNumber_ = std::max(largestNumber_, tool_);
                keyOf_[tool_] = tool_;
                selectKey(tool_, s);
            }
            define(spec, s);
        }
        if (!loaded_) fail(s, "motion before any CUTTER statement (missing CUTTER)");
        if (!cutters_.count(key_))
            fail(s, "tool " + std::to_string(tool_) + " has no CUTTER (missing CUTTER)");
    }

    /// Numbers the entries define() made, after the largest number the program names, so that
    /// none takes a number of the program's own; says which number each got.
    void numberNewTools() {
        if (newTools_.empty()) return;
        const auto numbered = [this](int key) { return key < 0 ? largestNumber_ - key : key; };
        for (Move& m : out_.path.moves) m.tool = numbered(m.tool);
        for (ToolChange& c : out_.path.toolChanges) c.tool = numbered(c.tool);
        for (std::size_t i = 0; i < newTools_.size(); ++i) {
            const int key = -int(i) - 1;
            auto node = cutters_.extract(key);
            node.key() = numbered(key);
            cutters_.insert(std::move(node));
            const NewTool& t = newTools_[i];
            diags_.note(t.where, "tool " + std::to_string(t.number) +
                                     " is described anew after it has cut (its moves before keep the CUTTER of line " +
                                     std::to_string(t.replacedLine) + "): the moves from here are tool T" +
                                     std::to_string(numbered(key)) + ", a number the program does not use");
        }
    }

    /// A position the program names, checked against kMaxCoordinateMm.
    Vec3 reachable(const Vec3& p, const Statement& s) const {
        if (!withinReach(p)) fail(s, "position " + detail::formatPoint(p) + " mm is beyond the 1e9 mm a program may reach");
        return p;
    }

    void emit(const Vec3& to, bool rapid, const Statement& s) {
        reachable(to, s);
        if (out_.path.moves.size() >= opt_.maxMoves) fail(s, detail::tooManyMoves(opt_.maxMoves, opt_.maxMovesReason));
        Move m;
        m.start = pos_;
        m.end = to;
        m.axis = axis_;
        if (posAxis_ != axis_) {
            m.startAxis = posAxis_;
            // The move's law turns the axis on the great circle between its ends: axes opposite
            // have none, refused here so that info and simulate both stop at the statement.
            try {
                const MotionLaw law(m);
            } catch (const Error& e) {
                const double degrees =
                    std::atan2(glm::length(glm::cross(posAxis_, axis_)), glm::dot(posAxis_, axis_)) * 180.0 / kPi;
                fail(s, "the tool axis turns " + detail::formatNumber(degrees) + " degrees during this move, from " +
                            detail::formatPoint(posAxis_) + " to " + detail::formatPoint(axis_) + ": " + e.what());
            }
        }
        m.tool = key_;
        m.rapid = rapid;
        m.source = {0, s.line};
        out_.path.moves.push_back(m);
        cutters_.at(key_).cut = true;
        pos_ = to;
        posAxis_ = axis_;
    }

    void gotoPoint(const Statement& s) {
        const auto v = numbers(s);
        if (v.size() != 3 && v.size() != 6) fail(s, "GOTO needs x,y,z or x,y,z,i,j,k");
        requireTool(s);
        const Vec3 p = reachable(toPart(Vec3(v[0], v[1], v[2]) * scale_), s);
        if (v.size() == 6) axis_ = toolAxisOf(s, v);
        const bool rapid = rapidNext_;
        rapidNext_ = false;
        if (!havePos_) {
            havePos_ = true;
            pos_ = p;
            posAxis_ = axis_;
            diags_.note(loc(s), "first GOTO without FROM: the tool starts there (no move)");
            if (!cycle_.active) return;
        }
        if (circle_) return arcTo(p, s);
        if (cycle_.active) return drill(p, s);
        emit(p, rapid, s);
    }

    /// FROM/x,y,z[,i,j,k] says where the tool is, with no move. Once the tool has a place, a FROM
    /// that puts it elsewhere skips the way between: a warning, since that is not simulated.
    void from(const Statement& s) {
        const auto v = numbers(s);
        if (v.size() != 3 && v.size() != 6) fail(s, "FROM needs x,y,z[,i,j,k]");
        const Vec3 p = reachable(toPart(Vec3(v[0], v[1], v[2]) * scale_), s);
        if (v.size() == 6) axis_ = toolAxisOf(s, v);
        if (havePos_ && (glm::length(p - pos_) > kRestatedPositionMm || axis_ != posAxis_)) {
            std::string msg = "FROM moves the tool from " + detail::formatPoint(pos_) + " to " + detail::formatPoint(p);
            if (axis_ != posAxis_)
                msg += " and its axis from " + detail::formatPoint(posAxis_) + " to " + detail::formatPoint(axis_);
            diags_.warn(loc(s), msg + " with no move: the way between is not simulated", "apt FROM jump");
        }
        pos_ = p;
        posAxis_ = axis_;
        havePos_ = true;
    }

    void godlta(const Statement& s) {
        const auto v = numbers(s);
        requireTool(s);
        if (!havePos_) fail(s, "GODLTA before any position (no FROM or GOTO)");
        Vec3 d;
        if (v.size() == 1) d = axis_ * (v[0] * scale_);
        else if (v.size() == 3) d = Vec3(v[0], v[1], v[2]) * scale_;
        else fail(s, "GODLTA needs d or dx,dy,dz");
        if (!world_ && haveCsys_ && v.size() == 3) d = rot_[0] * d.x + rot_[1] * d.y + rot_[2] * d.z;
        const bool rapid = rapidNext_;
        rapidNext_ = false;
        emit(pos_ + d, rapid, s);
    }

    void circle(const Statement& s) {
        const auto v = numbers(s);
        if (v.size() < 6) fail(s, "CIRCLE needs xc,yc,zc,i,j,k[,r,...]");
        if (circle_) fail(s, "CIRCLE follows CIRCLE without the GOTO that ends the first");
        if (!havePos_) fail(s, "CIRCLE before any position (no FROM or GOTO): the arc has no start");
        Circle c;
        c.centre = toPart(Vec3(v[0], v[1], v[2]) * scale_);
        c.axis = axisOf(s, v, 3, "CIRCLE axis");
        if (v.size() >= 7 && !(v[6] > 0)) fail(s.args[6], "CIRCLE radius must be positive");
        c.radius = v.size() >= 7 ? v[6] * scale_ : -1.0;
        circle_ = c;
        circleWhere_ = loc(s);
    }

    void arcTo(const Vec3& end, const Statement& s) {
        const Circle c = *circle_;
        circle_.reset();
        const Vec3 w = c.axis;
        const Vec3 ds = pos_ - c.centre, de = end - c.centre;
        const double hs = glm::dot(ds, w), he = glm::dot(de, w);
        const Vec3 us = ds - hs * w, ue = de - he * w;
        const double rs = glm::length(us), re = glm::length(ue);
        if (rs < 1e-9) throw ParseError(circleWhere_, "CIRCLE: the arc starts at its centre", std::string());
        if (std::abs(rs - re) > kArcRadiusAbsTol && std::abs(rs - re) > kArcRadiusRelTol * rs)
            fail(s, "CIRCLE: the GOTO end point is not on the circle (radius " + std::to_string(re) +
                        " vs " + std::to_string(rs) + " mm)");
        if (c.radius > 0 && std::abs(c.radius - rs) > kArcRadiusAbsTol && std::abs(c.radius - rs) > kArcRadiusRelTol * rs)
            throw ParseError(circleWhere_, "CIRCLE radius does not match the distance of the start point", std::to_string(c.radius));
        detail::ArcSpec arc;
        arc.u = us / rs;
        arc.w = w;
        arc.v = glm::cross(w, arc.u);
        arc.centre = c.centre;
        arc.startAngle = 0.0;
        double sweep = 2 * kPi;
        if (glm::length(ue - us) > 1e-9) {
            sweep = std::atan2(glm::dot(ue, arc.v), glm::dot(ue, arc.u));
            if (sweep <= 0) sweep += 2 * kPi;
        }
        arc.sweep = sweep;
        arc.startRadius = rs;
        arc.endRadius = re;
        arc.startHeight = hs;
        arc.endHeight = he;
        const std::size_t n = detail::arcSegments(std::max(rs, re), sweep, opt_.chordTolerance, opt_.maxArcSegments);
        if (n == 0) fail(s, "CIRCLE needs more chords than allowed at this tolerance");
        pts_.clear();
        detail::arcPoints(arc, n, pts_);
        pts_.back() = end;
        if (const double sag = detail::chordSag(std::max(rs, re), sweep, n); sag > out_.arcSag) {
            out_.arcSag = sag;
            out_.arcSagSource = {0, s.line};
        }
        const bool rapid = rapidNext_;
        rapidNext_ = false;
        const Vec3 endAxis = axis_;
        if (posAxis_ == endAxis) {
            for (const Vec3& p : pts_) emit(p, rapid, s);
            return;
        }
        // The axis turns over the whole arc as a GOTO's does over its move: on the great circle
        // from the start's axis to the end's, at a uniform rate, here in the arc's angle. Chord i
        // of n ends at the share (i + 1) / n of the arc, so it turns between the axes that law
        // has at i / n and (i + 1) / n (on the same great circle, at the same rate).
        Move whole;
        whole.start = pos_;
        whole.end = end;
        whole.startAxis = posAxis_;
        whole.axis = endAxis;
        std::optional<MotionLaw> law;
        try {
            law.emplace(whole);
        } catch (const Error& e) {
            fail(s, std::string("CIRCLE: the tool axis cannot turn from ") + detail::formatPoint(posAxis_) + " to " +
                        detail::formatPoint(endAxis) + " over the arc: " + e.what());
        }
        for (std::size_t i = 0; i < n; ++i) {
            axis_ = i + 1 == n ? endAxis : law->pose(double(i + 1) / double(n)).axis;
            emit(pts_[i], rapid, s);
        }
    }

    // ---- drilling cycles ----
    struct Cycle {
        bool active = false;
        std::string kind;
        double fedto = 0, rapto = 0, rtrcto = 0, incr = 0, first = 0, sub = 0;
        bool haveRtrcto = false;
    };

    void cycle(const Statement& s) {
        if (s.args.empty()) fail(s, "CYCLE needs a type");
        const std::string& kind = s.args[0].text;
        if (kind == "OFF") {
            cycle_.active = false;
            return ignoreArgs(s, 1, "CYCLE/OFF");
        }
        if (kind == "INIT" || kind == "CLEAR") return warnKind(s, "CYCLE/INIT and CYCLE/CLEAR ignored");
        if (kind != "DRILL" && kind != "DEEP" && kind != "DEEP2" && kind != "BRKCHP" && kind != "FACE")
            fail(s.args[0], "unsupported CYCLE type");
        Cycle c;
        c.active = true;
        c.kind = kind;
        bool haveFedto = false;
        for (std::size_t k = 1; k < s.args.size(); ++k) {
            const std::string& key = s.args[k].text;
            auto value = [&]() {
                if (k + 1 >= s.args.size()) fail(s.args[k], "CYCLE keyword without its value");
                return number(s.args[++k]);
            };
            if (key == "FEDTO") c.fedto = value() * scale_, haveFedto = true;
            else if (key == "RAPTO") c.rapto = value() * scale_;
            else if (key == "RTRCTO") c.rtrcto = value() * scale_, c.haveRtrcto = true;
            else if (key == "INCR") c.incr = value() * scale_;
            else if (key == "1STPECK") c.first = value() * scale_;
            else if (key == "SUBPECK") c.sub = value() * scale_;
            else if (key == "MMPM" || key == "IPM" || key == "MMPR" || key == "IPR") {
                value();
                warnKind(s, "cycle feed rate is not simulated (ignored)");
            } else if (key == "DWELL") {
                value();
                diags_.warn(loc(s.args[k]), "cycle dwell ignored (time is not simulated)", "apt dwell");
            } else if (isNumber(key)) {
                fail(s.args[k], "CYCLE value without keyword");
            } else {
                diags_.warn(loc(s.args[k]), "CYCLE keyword " + key + " ignored", "cycle " + key);
            }
        }
        if (!haveFedto) fail(s, "CYCLE without FEDTO depth");
        if (!c.haveRtrcto) c.rtrcto = c.rapto;
        if (kind == "DEEP" && !(c.incr > 0)) fail(s, "CYCLE/DEEP needs a positive INCR");
        if (kind == "DEEP2" || kind == "BRKCHP") {
            if (!(c.first > 0)) c.first = c.incr;
            if (!(c.sub > 0)) c.sub = c.first;
            if (!(c.first > 0)) fail(s, "CYCLE/" + kind + " needs a positive 1STPECK or INCR");
        } else {
            c.first = c.sub = c.incr;
        }
        cycle_ = c;
    }

    void drill(const Vec3& p, const Statement& s) {
        const Vec3 a = axis_;
        const Vec3 clear = p + cycle_.rtrcto * a;
        const Vec3 approach = p + cycle_.rapto * a;
        const double bottom = -cycle_.fedto;
        emit(clear, true, s);
        emit(approach, true, s);
        if (cycle_.kind == "DRILL" || cycle_.kind == "FACE" || !(cycle_.first > 0)) {
            emit(p + bottom * a, false, s);
        } else {
            double depth = cycle_.rapto;
            double step = cycle_.first;
            std::size_t guard = 0;
            while (depth - step > bottom) {
                if (++guard > opt_.maxArcSegments) fail(s, "too many pecks");
                if (depth < cycle_.rapto) emit(p + (depth + kPeckClearance) * a, true, s);
                depth -= step;
                emit(p + depth * a, false, s);
                emit(approach, true, s);
                step = cycle_.sub;
            }
            if (depth < cycle_.rapto) emit(p + (depth + kPeckClearance) * a, true, s);
            emit(p + bottom * a, false, s);
        }
        emit(clear, true, s);
    }

    /// Whether two CUTTER values printed in `unit` (mm per unit, for lengths in mm) may be the
    /// same value, each rounded as CL files print (cutterRounding).
    static bool roundsTo(double a, double b, double unit) {
        return std::abs(a - b) <= cutterRounding(a, unit) + cutterRounding(b, unit);
    }

    /// The ball end mill of diameter d a CUTTER describes with r = d/2 (and e = 0, f = r in the
    /// 7-value form) to the digits CL files print; where the values differ from those, a note
    /// names them, as they are replaced.
    Tool ball(const CutterSpec& spec, ToolLengths lengths) {
        const std::vector<double>& v = spec.params;
        const double d = v[0], r = v[1];
        const bool full = v.size() == 7;
        if (r != d / 2 || (full && (v[2] != 0.0 || v[3] != r))) {
            const auto [rText, halfD] = decimalsApart(r, d / 2);
            std::string values = "r = " + rText + " mm";
            if (full) values += ", e = " + detail::formatNumber(v[2]) + " mm, f = " + detail::formatNumber(v[3]) + " mm";
            diags_.note(spec.where, "CUTTER with " + values + " describes, to the digits CL files print, a ball end "
                                    "mill of diameter " + detail::formatNumber(d) + " mm (d/2 = " + halfD +
                                    " mm): taken as that ball");
        }
        return ballEndMill(d, lengths);
    }

    void buildTools() {
        for (auto& [n, spec] : cutters_) {
            const auto& v = spec.params;
            try {
                const double d = v[0];
                const double r = v.size() > 1 ? v[1] : 0.0;
                if (v.size() <= 2) {
                    ToolLengths lengths{spec.cuttingLength, 0.0};
                    if (r <= 0) out_.tools.insert_or_assign(n, flatEndMill(d, lengths));
                    else if (roundsTo(r, d / 2, spec.unit)) out_.tools.insert_or_assign(n, ball(spec, lengths));
                    else out_.tools.insert_or_assign(n, bullNoseEndMill(d, r, lengths));
                } else {
                    // CUTTER/d,r,e,f,alpha,beta,h.
                    const double e = v[2];
                    const double f0 = v[3];
                    const double alpha = v[4] * kPi / 180.0;
                    const double beta = v[5] * kPi / 180.0;
                    const double h = v[6];
                    // A pointed tip (drill) whose flank misses the axis by the rounding of
                    // printed values alone (f against e tan(alpha)) is snapped onto it.
                    double f = f0;
                    if (r == 0.0 && alpha > 0.0) {
                        const double pointed = e * std::tan(alpha), cosA = std::cos(alpha);
                        const double printed = cutterRounding(f, spec.unit) + cutterRounding(e, spec.unit) * std::tan(alpha) +
                                               e * cutterRounding(v[4], 1.0) * kPi / 180.0 / (cosA * cosA);
                        if (std::abs(f - pointed) <= printed) f = pointed;
                    }
                    double cutting = spec.cuttingLength;
                    if (h > 0 && cutting > h) cutting = h;
                    // APT's ball end mill, CUTTER/d,d/2,0,d/2,0,0,h: the ball the short form makes.
                    if (alpha == 0.0 && beta == 0.0 && roundsTo(e, 0.0, spec.unit) && roundsTo(r, d / 2, spec.unit) &&
                        roundsTo(f, r, spec.unit) && h > d / 2)
                        out_.tools.insert_or_assign(n, ball(spec, {cutting > 0.0 ? cutting : h, h}));
                    else
                        out_.tools.insert_or_assign(n, aptCutter(d, r, e, f, alpha, beta, h, cutting, spec.unit));
                }
            } catch (const ParseError&) {
                throw;
            } catch (const Error& err) {
                throw ParseError(spec.where, std::string("CUTTER describes no real tool: ") + err.what());
            }
        }
    }

    struct Circle {
        Vec3 centre{0.0};
        Vec3 axis{0, 0, 1};
        double radius = -1;
    };

    const AptOptions& opt_;
    std::string file_;
    Program& out_;
    detail::DiagnosticCollector diags_;
    const Statement* cur_ = nullptr;
    double scale_ = 1.0;
    bool world_ = false;
    bool haveCsys_ = false;
    Vec3 rot_[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};  ///< columns
    Vec3 trans_{0.0};
    Vec3 pos_{0.0};
    Vec3 axis_{0, 0, 1};
    Vec3 posAxis_{0, 0, 1};  ///< the axis the tool has at pos_: a move from there to a new axis_ turns
    bool havePos_ = false;
    bool rapidNext_ = false;
    /// MULTAX as last stated: SolidWorks CAM writes GOTO/x,y,z,i,j,k without any, so a program
    /// that never states it reads i,j,k as under MULTAX/ON.
    enum class Multax { Unstated, On, Off };
    Multax multax_ = Multax::Unstated;
    bool finished_ = false;
    /// A tool-table entry the reader made for a CUTTER (or a CSI_SET_FLUTE_LENGTH) that changed
    /// tool `number` after it had cut (define()).
    struct NewTool {
        int number = 0;
        SourceLocation where;  ///< the statement that changed it
        int replacedLine = 0;  ///< the CUTTER statement of the description it replaced
    };

    bool loaded_ = false;  ///< a tool is in the spindle: tool_ and key_ say which
    int tool_ = 0;         ///< the program's number of the tool in the spindle
    int key_ = 0;          ///< its entry in cutters_ and the tool table, which its moves name
    int largestNumber_ = 0;  ///< of the tool numbers the program names
    std::map<int, int> keyOf_;  ///< the entry each tool number names now
    std::vector<NewTool> newTools_;  ///< entry -1 - i is newTools_[i] until numberNewTools()
    std::optional<CutterSpec> pending_;  ///< a CUTTER that no LOAD/TOOL has claimed yet
    std::map<int, CutterSpec> cutters_;  ///< by entry
    std::optional<Circle> circle_;
    SourceLocation circleWhere_;
    Cycle cycle_;
    std::vector<Vec3> pts_;
};

}  // namespace

Program parseApt(std::string_view text, const std::string& fileName, const AptOptions& options) {
    Program program;
    AptReader reader(options, fileName, program);
    reader.run(text);
    return program;
}

Program readApt(const std::string& path, const AptOptions& options) {
    return parseApt(detail::readTextFile(path), path, options);
}

}  // namespace dexelmill
