// jsonTextFault: nesting past kMaxJsonDepth and keys given twice, found by reading the text as
// written; strings and comments hide brackets, quotes and keys.
#include <catch2/catch.hpp>

#include <string>

#include "dexelmill/io/json_text.h"

using namespace dexelmill;

namespace {

/// `depth` arrays, one inside the other, around 1.
std::string nested(int depth) { return std::string(std::size_t(depth), '[') + "1" + std::string(std::size_t(depth), ']'); }

}  // namespace

TEST_CASE("JSON text: nesting as deep as allowed, and one level more", "[io][json]") {
    CHECK_FALSE(jsonTextFault(nested(kMaxJsonDepth), false));
    const auto deeper = jsonTextFault(nested(kMaxJsonDepth + 1), false);
    REQUIRE(deeper);
    CHECK(deeper->byte == std::size_t(kMaxJsonDepth));  // the first bracket past the limit
    CHECK(deeper->message == "arrays and objects are nested deeper than 64 levels");
    // The file that overflowed the stack: found at the same bracket, however deep it goes on.
    const auto huge = jsonTextFault("{\"axes\":" + nested(60000) + "}", false);
    REQUIRE(huge);
    CHECK(huge->byte == 8 + std::size_t(kMaxJsonDepth) - 1);
    // Objects count as arrays do; closing brackets give the levels back.
    std::string siblings = "[";
    for (int i = 0; i < 100; ++i) siblings += (i ? "," : "") + nested(kMaxJsonDepth - 1);
    CHECK_FALSE(jsonTextFault(siblings + "]", false));
    CHECK(jsonTextFault(std::string(65, '{'), false));
}

TEST_CASE("JSON text: a key twice in one object, and keys that only look alike", "[io][json]") {
    const std::string twice = R"({"letter": "A", "direction": [1, 0, 0], "direction": [0, 1, 0]})";
    const auto fault = jsonTextFault(twice, false);
    REQUIRE(fault);
    CHECK(fault->byte == twice.rfind("\"direction\""));
    CHECK(fault->message == "the key \"direction\" is given twice in one object");
    // The same key in two objects, in an object and the one inside it, as a value, or in an array.
    CHECK_FALSE(jsonTextFault(R"({"axes": [{"letter": "A"}, {"letter": "C"}], "letter": {"letter": "letter"}})", false));
    CHECK_FALSE(jsonTextFault(R"(["a", "a", {"a": 1}])", false));
    // After a nested object closes, its parent's next key is still checked against the parent's.
    CHECK(jsonTextFault(R"({"a": {"b": 1, "c": 2}, "a": 3})", false));
}

TEST_CASE("JSON text: brackets and quotes inside strings and comments", "[io][json]") {
    // A string holding brackets, an escaped quote and a backslash before its closing quote.
    CHECK_FALSE(jsonTextFault(R"({"name": "[[[{{{\"}}} \\", "axes": []})", false));
    const std::string deepInString = "{\"name\": \"" + nested(100) + "\"}";
    CHECK_FALSE(jsonTextFault(deepInString, false));
    // CAMotics projects may hold comments; their text is no JSON.
    const std::string commented = "{\n  // \"units\": [[[[\n  \"units\": \"metric\" /* \"units\" {{{ */\n}";
    CHECK_FALSE(jsonTextFault(commented, true));
    // Without comments, what is in them counts (and the JSON library refuses the file).
    CHECK(jsonTextFault("{\"a\": 1, /* \"a\" */ \"a\": 2}", false));
    // Unterminated strings and comments are the library's to refuse.
    CHECK_FALSE(jsonTextFault("{\"a\": \"[[[", false));
    CHECK_FALSE(jsonTextFault("{/* [[[", true));
}

TEST_CASE("JSON text: a number beyond the range of a double", "[io][json]") {
    const auto big = jsonTextFault("[1, 1e999]", false);
    REQUIRE(big);
    CHECK(big->byte == 4);
    CHECK(big->message == "the number 1e999 is beyond the range of a double");
    const auto negative = jsonTextFault("{\"a\": -2.5E+400}", false);
    REQUIRE(negative);
    CHECK(negative->byte == 6);
    CHECK(negative->message == "the number -2.5E+400 is beyond the range of a double");
    // The largest double, one that rounds to zero (as the library takes it), and numbers in
    // strings, keys and comments.
    CHECK_FALSE(jsonTextFault("[1.7976931348623157e308, -1e-999, 0, -0.5e-3]", false));
    CHECK_FALSE(jsonTextFault(R"({"1e999": "1e999"})", false));
    CHECK_FALSE(jsonTextFault("[1 /* 1e999 */, 2 // 1e999\n]", true));
    // The first fault in reading order.
    const auto first = jsonTextFault(R"({"a": 1e999, "a": 1})", false);
    REQUIRE(first);
    CHECK(first->byte == 6);
}

// JsonPositions: where each value and key begins, by JSON pointer. The expected offsets are
// counted by hand on the texts below (0 is the first character).
namespace {

/// The offset of the value at `pointer`, -1 when there is none.
long at(const JsonPositions& p, const std::string& pointer) {
    const auto b = p.byteOf(pointer);
    return b ? long(*b) : -1;
}

/// The offset of the key naming `pointer`, -1 when there is none.
long keyAt(const JsonPositions& p, const std::string& pointer) {
    const auto b = p.keyByteOf(pointer);
    return b ? long(*b) : -1;
}

}  // namespace

TEST_CASE("JSON positions: nested objects and arrays", "[io][json]") {
    //                       0         1         2         3
    //                       0123456789012345678901234567890
    const JsonPositions p(R"({"a": [1, {"b": "x"}], "c": {}})", false);
    CHECK(at(p, "") == 0);
    CHECK(keyAt(p, "/a") == 1);
    CHECK(at(p, "/a") == 6);
    CHECK(at(p, "/a/0") == 7);
    CHECK(at(p, "/a/1") == 10);
    CHECK(keyAt(p, "/a/1/b") == 11);
    CHECK(at(p, "/a/1/b") == 16);
    CHECK(keyAt(p, "/c") == 23);
    CHECK(at(p, "/c") == 28);
    // What the text does not hold, and array elements and the root, which have no key.
    CHECK(at(p, "/a/2") == -1);
    CHECK(at(p, "/b") == -1);
    CHECK(at(p, "/a/1/b/0") == -1);
    CHECK(at(p, "a") == -1);
    CHECK(keyAt(p, "/a/0") == -1);
    CHECK(keyAt(p, "") == -1);
    // Arrays in arrays, empty ones included, and a root that is no object.
    const JsonPositions q("[[],[[7]]]", false);
    CHECK(at(q, "/0") == 1);
    CHECK(at(q, "/1") == 4);
    CHECK(at(q, "/1/0") == 5);
    CHECK(at(q, "/1/0/0") == 6);
    CHECK(at(q, "/0/0") == -1);
    CHECK(at(JsonPositions(" 42 ", false), "") == 1);
}

TEST_CASE("JSON positions: quotes and brackets inside strings", "[io][json]") {
    // An escaped quote and brackets inside a string, then true and null.
    //                       0         1         2         3
    //                       01234567890123456789012345678901234
    const JsonPositions p(R"({"s": "a\"]}[{", "t": [true, null]})", false);
    CHECK(at(p, "/s") == 6);
    CHECK(keyAt(p, "/t") == 17);
    CHECK(at(p, "/t") == 22);
    CHECK(at(p, "/t/0") == 23);
    CHECK(at(p, "/t/1") == 29);
    // A string ending in an escaped backslash.
    const JsonPositions b(R"({"u": "\\", "v": 1})", false);
    CHECK(at(b, "/u") == 6);
    CHECK(keyAt(b, "/v") == 12);
    CHECK(at(b, "/v") == 17);
}

TEST_CASE("JSON positions: comments, CRLF and a byte order mark", "[io][json]") {
    // A key inside a line comment and a brace inside a block comment between a key and its colon.
    const std::string text = "{\r\n  // \"x\": [\r\n  \"x\" /* { */ : 5\r\n}";
    const JsonPositions p(text, true);
    CHECK(at(p, "") == 0);
    CHECK(keyAt(p, "/x") == 18);
    CHECK(at(p, "/x") == 32);
    // Without comments the text is no JSON: what stands before the comment is kept.
    const JsonPositions strict(text, false);
    CHECK(at(strict, "") == 0);
    CHECK(at(strict, "/x") == -1);
    // A comment before the root, and between a number and its comma.
    const JsonPositions before("/* c */ [1]", true);
    CHECK(at(before, "") == 8);
    CHECK(at(before, "/0") == 9);
    const JsonPositions after("[1/*c*/,2]", true);
    CHECK(at(after, "/0") == 1);
    CHECK(at(after, "/1") == 8);
    // Tabs and newlines as blanks, and a UTF-8 byte order mark, which the JSON library skips.
    const JsonPositions blanks("\t[\n\t1\n]", false);
    CHECK(at(blanks, "") == 1);
    CHECK(at(blanks, "/0") == 4);
    const JsonPositions bom("\xef\xbb\xbf{\"a\": 1}", false);
    CHECK(at(bom, "") == 3);
    CHECK(at(bom, "/a") == 9);
}

TEST_CASE("JSON positions: keys as pointer tokens, escapes decoded", "[io][json]") {
    CHECK(jsonPointerToken("a/b") == "a~1b");
    CHECK(jsonPointerToken("m~n") == "m~0n");
    CHECK(jsonPointerToken("~1") == "~01");  // "~" first: "~1" read back is "~1", not "/"
    CHECK(jsonPointerToken("") == "");
    //                       0         1         2         3         4
    //                       01234567890123456789012345678901234567890
    const JsonPositions p(R"({"a/b": 1, "m~n": 2, "": 3, "\u0061~": 4})", false);
    CHECK(keyAt(p, "/a~1b") == 1);
    CHECK(at(p, "/a~1b") == 8);
    CHECK(keyAt(p, "/m~0n") == 11);
    CHECK(at(p, "/m~0n") == 18);
    CHECK(keyAt(p, "/") == 21);  // the empty key
    CHECK(at(p, "/") == 25);
    CHECK(keyAt(p, "/a~0") == 28);
    CHECK(at(p, "/a~0") == 39);
    CHECK(at(p, "/a/b") == -1);
    // A surrogate pair is one character (U+1F600 in UTF-8), and \n a newline.
    CHECK(at(JsonPositions(R"({"\ud83d\ude00": 0})", false), "/\xf0\x9f\x98\x80") == 17);
    CHECK(at(JsonPositions(R"({"a\nb": 0})", false), "/a\nb") == 9);
    // A key given twice: the last counts, as in the JSON library.
    const JsonPositions twice(R"({"k": 1, "k": 2})", false);
    CHECK(keyAt(twice, "/k") == 9);
    CHECK(at(twice, "/k") == 14);
}

TEST_CASE("JSON positions: text that is no JSON keeps what stands before the fault", "[io][json]") {
    const JsonPositions missingComma(R"({"a": 1 "b": 2})", false);
    CHECK(at(missingComma, "/a") == 6);
    CHECK(at(missingComma, "/b") == -1);
    CHECK(at(JsonPositions(R"({"a": "xx)", false), "/a") == 6);
    CHECK(at(JsonPositions("[1,", false), "/0") == 1);
    CHECK(at(JsonPositions("{\"a\" 1}", false), "/a") == -1);
    CHECK(at(JsonPositions("[,]", false), "/0") == -1);
    CHECK(at(JsonPositions("", false), "") == -1);
    CHECK(at(JsonPositions("/* open", true), "") == -1);
}

TEST_CASE("JSON places: lines and columns of values and keys, counted by hand", "[io][json]") {
    // Line 1 "{", line 2 two blanks then "a": 1, line 3 a tab then "b": [true].
    const std::string text = "{\n  \"a\": 1,\n\t\"b\": [true]\n}";
    const JsonPlaces places(text, "m.json", false);
    const auto place = [](const SourceLocation& at) { return at.str(); };
    CHECK(place(places.value("")) == "m.json:1:1");
    CHECK(place(places.key("/a")) == "m.json:2:3");
    CHECK(place(places.value("/a")) == "m.json:2:8");
    CHECK(place(places.key("/b")) == "m.json:3:2");
    CHECK(place(places.value("/b/0")) == "m.json:3:8");
    // What the text does not hold: the file alone.
    CHECK(place(places.value("/c")) == "m.json");
    CHECK(place(places.key("")) == "m.json");
    // Offsets: the first byte, a newline (the end of its line), and past the end.
    CHECK(place(locateByte(text, 0, "m.json")) == "m.json:1:1");
    CHECK(place(locateByte(text, 1, "m.json")) == "m.json:1:2");
    CHECK(place(locateByte(text, 2, "m.json")) == "m.json:2:1");
    CHECK(place(locateByte("ab", 99, "m.json")) == "m.json:1:3");
    CHECK(place(locateByte("", 0, "")) == "<input>:1:1");
}
