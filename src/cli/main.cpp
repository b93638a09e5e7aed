// dexelmill: the command-line tool. It parses options, calls the library and prints; nothing else.
#include <iostream>

#include <CLI/CLI.hpp>

#include "dexelmill/error.h"

int main(int argc, char** argv) {
    CLI::App app{
        "dexelmill " DEXELMILL_VERSION
        " - predicts the part a CNC milling program cuts from a block of stock, with a tri-dexel\n"
        "stock model and exact swept tool envelopes. Lengths are in mm, angles in degrees."};
    app.set_version_flag("--version", std::string("dexelmill ") + DEXELMILL_VERSION);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e) == 0 ? 0 : 2;
    }
    try {
        std::cout << app.help();
    } catch (const dexelmill::Error& e) {
        std::cerr << e.what() << "\n";
        return 1;
    }
    return 0;
}
