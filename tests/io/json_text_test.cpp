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
