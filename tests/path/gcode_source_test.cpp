// The G-code reader's line table: lines, O-word lines and N numbers are found as written, and a
// plain line (blank, comment or move) costs a few bytes (issue 15).
#include <catch2/catch.hpp>

#include <string>

#include "dexelmill/job/memory.h"
#include "dexelmill/path/gcode.h"
#include "path/detail/gcode_source.h"

using namespace dexelmill;
using detail::OKind;
using detail::SourceFile;

TEST_CASE("gcode source: lines without their ends, O-word lines and N numbers", "[path][gcode]") {
    const SourceFile f("f.ngc",
                       "%\r\n"
                       "N10 G0 X1 (move)\n"
                       "\n"
                       "o<Pocket Side> sub\r\n"
                       "  O0097 repeat [2]\n"
                       "N20 o0097 endrepeat\n"
                       "WHILE [#1 LT 2] DO12\n"
                       "END12\n"
                       "/ o3 if [1]\n"
                       "o100\n"
                       "last");
    REQUIRE(f.lineCount() == 11);
    CHECK(f.line(0) == "%");
    CHECK(f.line(1) == "N10 G0 X1 (move)");
    CHECK(f.line(2).empty());
    CHECK(f.line(3) == "o<Pocket Side> sub");
    CHECK(f.line(10) == "last");
    CHECK(SourceFile::lineNumber(10) == 11);
    CHECK(f.startsWithPercent());

    for (int k : {0, 1, 2, 10}) CHECK(f.oword(k) == nullptr);
    REQUIRE(f.owords().size() == 7);
    CHECK(f.oword(3)->kind == OKind::Sub);
    CHECK(f.oword(3)->label == "pocketside");
    CHECK(f.oword(4)->kind == OKind::Repeat);
    CHECK(f.oword(4)->label == "97");
    CHECK(f.line(4).substr(f.oword(4)->argPos) == " [2]");
    CHECK(f.oword(5)->kind == OKind::EndRepeat);
    CHECK(f.oword(5)->label == "97");
    CHECK(f.oword(6)->kind == OKind::FanucWhile);
    CHECK(f.oword(6)->label == "12");
    CHECK(f.oword(7)->kind == OKind::FanucEnd);
    CHECK(f.oword(8)->kind == OKind::If);
    CHECK(f.oword(9)->kind == OKind::Label);
    CHECK(f.oword(9)->label == "100");

    // Every line but the blank one holds more than a comment.
    CHECK(f.contentLines() == 10);
    CHECK(SourceFile("c.ngc", "(a)\n  ; b\n\n\t\nG0 X1 (c)\n").contentLines() == 1);
    CHECK(f.lineOfN(10) == 1);
    CHECK(f.lineOfN(20) == 5);
    CHECK(f.lineOfN(30) == -1);

    const SourceFile empty("e.ngc", "");
    CHECK(empty.lineCount() == 1);
    CHECK(empty.line(0).empty());
    CHECK_FALSE(empty.startsWithPercent());
    const SourceFile endsWithNewline("n.ngc", "G0 X1\n");
    CHECK(endsWithNewline.lineCount() == 2);
    CHECK(endsWithNewline.line(1).empty());
}

TEST_CASE("gcode source: a million blank lines cost a few bytes each", "[path][gcode]") {
    constexpr std::size_t kLines = 2'000'000;
    const std::string text = "G0 X0 Y0 Z5\n" + std::string(kLines, '\n') + "(end)\nG1 X1\n";
    if (!resetPeakMemory()) {
        WARN("the system does not let the peak memory be reset; the figure is not measured");
        return;
    }
    const double before = currentMemoryMb();
    const Program p = parseGcode(text, "blank.ngc");
    const double grownBytes = (peakMemoryMb() - before) * 1024.0 * 1024.0;
    CHECK(p.path.moves.size() == 1);
    // The line table is one offset (8 bytes) and one bit per line, and the reader copies the
    // text (1 byte per line here). Before, a line cost 88 bytes of table and 100 of reserved moves.
    constexpr double kBytesPerLine = 16.0;
    constexpr double kSlackBytes = 8.0 * 1024 * 1024;
    INFO("grew " << grownBytes / double(kLines) << " bytes per line");
    CHECK(grownBytes < kBytesPerLine * double(kLines) + kSlackBytes);
}
