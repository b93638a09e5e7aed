// Program files as users have them: byte-order marks, every kind of line end, control bytes in
// messages, and paths that are not files (issue 15).
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "dexelmill/error.h"
#include "dexelmill/path/camotics.h"
#include "dexelmill/machine/kinematics.h"
#include "dexelmill/path/gcode.h"
#include "support/scratch.h"

using namespace dexelmill;
namespace fs = std::filesystem;

namespace {

/// A folder of its own under the system's temporary folder, removed at the end.
class Folder {
public:
    explicit Folder(const std::string& name) : dir_(testing::scratchFolder("dexelmill_files_", name)) {}
    ~Folder() {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }
    std::string write(const std::string& name, const std::string& bytes) const {
        const fs::path p = dir_ / name;
        std::ofstream(p, std::ios::binary) << bytes;
        return p.string();
    }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }

private:
    fs::path dir_;
};

/// The moves of a program as text, to compare two readings.
std::string movesOf(const Program& p) {
    std::string s;
    for (const Move& m : p.path.moves)
        s += std::to_string(m.end.x) + "," + std::to_string(m.end.y) + "," + std::to_string(m.end.z) + ":" +
             std::to_string(m.source.line) + ";";
    return s;
}

std::string errorOf(const std::string& path) {
    try {
        readProgram(path);
    } catch (const Error& e) {
        return e.what();
    }
    return "no error";
}

}  // namespace

TEST_CASE("files: a byte-order mark and CR, LF or CRLF line ends read alike", "[path][files]") {
    const Folder dir("line_ends");
    const std::string lines[] = {"G21 G90", "G0 X0 Y0 Z5", "G1 Z-1", "G1 X10 Y4", "G1 X3 (comment)", "M2"};
    auto join = [&](const std::string& end) {
        std::string s;
        for (const std::string& l : lines) s += l + end;
        return s;
    };
    const Program lf = readProgram(dir.write("lf.ngc", join("\n")));
    REQUIRE(lf.path.moves.size() == 3);  // the first G0 only sets the unknown start
    CHECK(lf.path.moves.back().source.line == 5);
    const std::string bom = "\xEF\xBB\xBF";
    for (const auto& [name, text] : {std::pair<std::string, std::string>{"crlf.ngc", join("\r\n")},
                                     {"cr.ngc", join("\r")},
                                     {"bom.ngc", bom + join("\n")},
                                     {"bom_crlf.ngc", bom + join("\r\n")},
                                     {"bom_cr.ngc", bom + join("\r")}}) {
        INFO(name);
        CHECK(movesOf(readProgram(dir.write(name, text))) == movesOf(lf));
    }
    // APT and a project alike.
    const std::string apt = "UNITS/MM\rCUTTER/6\rFROM/0,0,5\rGOTO/10,0,-1\rGOTO/10,8,-1\r";
    const Program a = readProgram(dir.write("part.apt", bom + apt));
    REQUIRE(a.path.moves.size() == 2);
    CHECK(a.path.moves.back().source.line == 5);
    // A machine has nothing to do with APT, whose GOTOs give the axis in the part frame: said so.
    GcodeOptions withMachine;
    withMachine.machine = loadMachine("xyzac-trt");
    const Program am = readProgram(dir.write("machine.apt", apt), withMachine);
    REQUIRE_FALSE(am.diagnostics.empty());
    CHECK_THAT(am.diagnostics.front().message, Catch::Matchers::Contains("--machine xyzac-trt is not used"));
    CHECK(movesOf(am) == movesOf(a));
    dir.write("p.ngc", join("\r\n"));
    const Program project =
        readProgram(dir.write("p.camotics", bom + "{\r\"units\": \"metric\",\r\"files\": [\"p.ngc\"]\r}\r"));
    CHECK(movesOf(project) == movesOf(lf));
    // A column after a byte-order mark counts from the first character the user sees.
    try {
        readProgram(dir.write("bad.ngc", bom + "G1 X1 @\n"));
        FAIL("no error");
    } catch (const ParseError& e) {
        CHECK(e.where().line == 1);
        CHECK(e.where().column == 7);
    }
}

TEST_CASE("files: what is not a regular file is refused before it is read", "[path][files]") {
    const Folder dir("not_files");
    fs::create_directories(dir.path("folder.ngc"));
    CHECK_THAT(errorOf(dir.path("folder.ngc")), Catch::Matchers::Contains("is a directory"));
    CHECK_THAT(errorOf(dir.path("missing.ngc")), Catch::Matchers::Contains("no such file"));
    if (fs::exists("/dev/zero"))
        CHECK_THAT(errorOf("/dev/zero"), Catch::Matchers::Contains("not a regular file"));
    // A project that lists a folder says so, rather than running no moves.
    dir.write("p.camotics", "{\"files\": [\"folder.ngc\"]}");
    CHECK_THAT(errorOf(dir.path("p.camotics")), Catch::Matchers::Contains("is a directory"));
}

TEST_CASE("files: a mesh or a level set is refused as a program, naming the file and what a program is",
          "[path][files][errors]") {
    const Folder dir("solids");
    // A binary STL's header and count, and an ASCII one: read as G-code, a mesh failed at a word of
    // its header ("olid" of an ASCII STL's "solid"), which did not say what the file is.
    const std::string binary = std::string(80, ' ') + std::string("\x0c\x00\x00\x00", 4) + std::string(600, '\x01');
    for (const auto& [name, bytes, kind] :
         {std::tuple<const char*, std::string, const char*>{"part.stl", binary, "an STL mesh"},
          {"part.STL", "solid part\nendsolid part\n", "an STL mesh"},
          {"part.obj", "v 0 0 0\n", "an OBJ mesh"},
          {"part.ply", "ply\n", "a PLY mesh"},
          {"part.vdb", std::string("\x20\x42\x44\x56\x00\x00\x00\x00", 8), "an OpenVDB level set"}}) {
        INFO(name);
        const std::string path = dir.write(name, bytes);
        CHECK(errorOf(path) == "'" + path + "' is " + kind +
                                   ", not a program: a program is G-code, an APT CL file or a CAMotics project; a "
                                   "solid is given with --stock or --design (.stl or .vdb)");
    }
    // A project that lists one says so too.
    dir.write("p.camotics", "{\"files\": [\"part.stl\"]}");
    CHECK_THAT(errorOf(dir.path("p.camotics")), Catch::Matchers::Contains("part.stl' is an STL mesh, not a program"));
}

TEST_CASE("files: control bytes in a message are escaped, and NUL does not cut it", "[path][files]") {
    const Folder dir("control");
    const std::string nul(4096, '\0');
    const std::string message = errorOf(dir.write("nul.ngc", nul));
    CHECK_THAT(message, Catch::Matchers::Contains("'\\x00"));
    CHECK(message.find('\0') == std::string::npos);
    const std::string esc = errorOf(dir.write("esc.ngc", "G1 X1 \x1b[31m\n"));
    CHECK_THAT(esc, Catch::Matchers::Contains("\\x1b"));
    CHECK(esc.find('\x1b') == std::string::npos);
    CHECK(printable("a\tb\x7f") == "a\tb\\x7f");
    // Well-formed UTF-8 stays (a degree sign, a euro sign, an emoji); a byte of Latin-1, a lone
    // continuation, an overlong form, a surrogate and a sequence cut short are escaped.
    CHECK(printable("30\xc2\xb0 \xe2\x82\xac \xf0\x9f\x94\xa7") == "30\xc2\xb0 \xe2\x82\xac \xf0\x9f\x94\xa7");
    CHECK(printable("30\xb0") == "30\\xb0");
    CHECK(printable("\x80x") == "\\x80x");
    CHECK(printable("\xc0\xaf") == "\\xc0\\xaf");
    CHECK(printable("\xed\xa0\x80") == "\\xed\\xa0\\x80");
    CHECK(printable("\xe2\x82") == "\\xe2\\x82");
}

TEST_CASE("files: a FileSource serves a project's programs and subroutine files", "[path][files]") {
    // The same project read from disk and from a map gives the same moves.
    const std::map<std::string, std::string> files = {
        {"p.camotics", "{\"units\": \"metric\", \"files\": [\"a.ngc\", \"b.apt\"]}"},
        {"a.ngc", "G21 G90\nG0 X0 Y0 Z5\no<step> call [3]\nM2\n"},
        {"step.ngc", "o<step> sub\nG1 X#1 Z-1 F100\no<step> endsub\n"},
        {"b.apt", "\xEF\xBB\xBF" "CUTTER/6\rFROM/0,0,5\rGOTO/4,0,-1\r"},
    };
    const Folder dir("source");
    for (const auto& [name, text] : files) dir.write(name, text);
    const Program fromDisk = readProgram(dir.path("p.camotics"));

    std::vector<std::string> asked;
    GcodeOptions options;
    options.files = [&](const std::string& path) -> std::optional<std::string> {
        asked.push_back(path);
        const auto it = files.find(path);
        if (it == files.end()) return std::nullopt;
        return it->second;
    };
    const Program fromMap = readProgram("p.camotics", options);
    REQUIRE(fromMap.path.moves.size() == 2);  // the subroutine's G1 and the APT GOTO
    CHECK(movesOf(fromMap) == movesOf(fromDisk));
    // The subroutine file was looked up beside its caller, in the map; the BOM and CR of the APT
    // file were normalised as on disk.
    CHECK(std::count(asked.begin(), asked.end(), "step.ngc") == 1);

    // A program that names a missing file says which.
    CHECK_THROWS_WITH(readGcodeFiles({"a.ngc", "gone.ngc"}, options), Catch::Matchers::Contains("'gone.ngc'"));
}

TEST_CASE("files: a call of an undefined subroutine says which file was looked for", "[path][files][errors]") {
    // LinuxCNC finds o<name> in name.ngc on its SUBROUTINE_PATH; dexelmill beside the caller, and
    // the error names that file, whether it is missing or does not define the subroutine.
    const std::map<std::string, std::string> files = {
        {"jobs/main.ngc", "G0 X0 Y0 Z5\no<gone> call\n"},
        {"jobs/other.ngc", "G0 X0 Y0 Z5\no<wrong> call\n"},
        {"jobs/wrong.ngc", "o<right> sub\nG1 X1 F100\no<right> endsub\n"},
    };
    GcodeOptions options;
    options.files = [&](const std::string& path) -> std::optional<std::string> {
        const auto it = files.find(path);
        if (it == files.end()) return std::nullopt;
        return it->second;
    };
    const auto messageOf = [&](const std::string& name) {
        try {
            readGcodeFiles({name}, options);
        } catch (const ParseError& e) {
            CHECK(e.where().file == name);
            CHECK(e.where().line == 2);
            return std::string(e.what());
        }
        FAIL("no error");
        return std::string();
    };
    CHECK_THAT(messageOf("jobs/main.ngc"),
               Catch::Matchers::Contains("o<gone>: the program does not define it, and there is no file jobs/gone.ngc"));
    CHECK_THAT(messageOf("jobs/other.ngc"),
               Catch::Matchers::Contains("o<wrong>: the program does not define it, nor does jobs/wrong.ngc"));
}
