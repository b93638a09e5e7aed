/// Writing outputs so that nothing is lost (io/atomic_file.h): a temporary file beside the
/// target, renamed over it once whole; batches renamed together; links, modes, owners, FIFOs,
/// devices and open descriptors; and outputs that would overwrite inputs or one another.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include <fcntl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <unistd.h>

#include "dexelmill/error.h"
#include "dexelmill/io/atomic_file.h"
#include "dexelmill/io/picture.h"
#include "support/temp_dir.h"

using namespace dexelmill;
using testing::slurp;
using testing::TempDir;
namespace fs = std::filesystem;

TEST_CASE("atomic write: a failed writer leaves the target and the directory untouched", "[io]") {
    TempDir dir;
    const std::string target = dir.file("out.txt");
    writeStreamAtomically(target, [](std::ostream& out) { out << "first"; });
    CHECK(slurp(target) == "first");
    CHECK_THROWS_AS(writeStreamAtomically(target,
                                          [](std::ostream& out) {
                                              out << "half";
                                              throw Error("boom");
                                          }),
                    Error);
    CHECK(slurp(target) == "first");
    CHECK(dir.entries() == 1);  // no temporary left behind
    writeStreamAtomically(target, [](std::ostream& out) { out << "second"; });
    CHECK(slurp(target) == "second");
    CHECK(dir.entries() == 1);
    CHECK_THROWS_AS(writeStreamAtomically(dir.file("no/such/dir/x"), [](std::ostream&) {}), Error);
}

TEST_CASE("output batch: the files are renamed together on commit, and none when one fails", "[io]") {
    TempDir dir;
    const std::string a = dir.file("a.txt"), b = dir.file("b.txt");
    std::ofstream(a) << "old a";
    std::ofstream(b) << "old b";
    {
        OutputBatch batch;
        writeStreamAtomically(a, [](std::ostream& out) { out << "new a"; }, &batch);
        writeStreamAtomically(b, [](std::ostream& out) { out << "new b"; }, &batch);
        CHECK(slurp(a) == "old a");  // staged, not yet renamed
        CHECK(dir.entries() == 4);
        CHECK_THROWS_WITH(writeStreamAtomically(dir.file("c.txt"),
                                                [](std::ostream& out) {
                                                    out << "half";
                                                    throw Error("disk full");
                                                },
                                                &batch),
                          "disk full");
    }
    CHECK(slurp(a) == "old a");
    CHECK(slurp(b) == "old b");
    CHECK(dir.entries() == 2);  // the batch removed its temporary files
    OutputBatch batch;
    writeStreamAtomically(a, [](std::ostream& out) { out << "new a"; }, &batch);
    writeStreamAtomically(b, [](std::ostream& out) { out << "new b"; }, &batch);
    batch.commit();
    CHECK(slurp(a) == "new a");
    CHECK(slurp(b) == "new b");
    CHECK(dir.entries() == 2);
}

TEST_CASE("output batch: a rename that fails puts back the files renamed before it", "[io]") {
    TempDir dir;
    fs::create_directories(dir.path / "later");
    const std::string replaced = dir.file("a.txt"), added = dir.file("new.txt"),
                      last = dir.file("later/b.txt");
    std::ofstream(replaced) << "old a";
    ::chmod(replaced.c_str(), 0640);
    const std::string other = dir.file("other link to a");
    REQUIRE(::link(replaced.c_str(), other.c_str()) == 0);
    struct stat before {};
    REQUIRE(::stat(replaced.c_str(), &before) == 0);
    OutputBatch batch;
    for (const std::string& target : {replaced, added, last})
        writeStreamAtomically(
            target, [](std::ostream& out) { out << "new"; }, &batch);
    // The last target's folder goes, with its staged file: its rename fails after the other two.
    fs::remove_all(dir.path / "later");
    CHECK_THROWS_WITH(batch.commit(), Catch::Contains("cannot rename") &&
                                          Catch::Contains("later/b.txt") &&
                                          Catch::Contains("no file was changed"));
    // The replaced file is back, the same file with its mode; the new one is gone, and no backup
    // or temporary file is left.
    struct stat after {};
    REQUIRE(::stat(replaced.c_str(), &after) == 0);
    CHECK(after.st_ino == before.st_ino);
    CHECK((after.st_mode & 07777) == 0640);
    CHECK(slurp(replaced) == "old a");
    CHECK(slurp(other) == "old a");
    CHECK_FALSE(fs::exists(added));
    CHECK(dir.entries() == 2);
    // Committed whole, the batch leaves no backup either, and the other link keeps the old file.
    OutputBatch again;
    for (const std::string& target : {replaced, added})
        writeStreamAtomically(
            target, [](std::ostream& out) { out << "new"; }, &again);
    again.commit();
    CHECK(slurp(replaced) == "new");
    CHECK(slurp(added) == "new");
    CHECK(slurp(other) == "old a");
    CHECK(dir.entries() == 3);
}

TEST_CASE("atomic write: the temporary files alive are what an interruption removes", "[io]") {
    TempDir dir;
    std::ofstream(dir.file("kept.txt")) << "old";
    OutputBatch batch;
    std::string first;
    batch.stage(dir.file("first.txt"), [&](const std::string& temp) {
        first = temp;
        std::ofstream(temp) << "new";
    });
    REQUIRE(fs::exists(first));
    // What the signal handler does, called in the middle of the second file's write: both staged
    // files go, the targets stay as they were, and the write fails as on a full disk.
    CHECK_THROWS_AS(batch.stage(dir.file("kept.txt"),
                                [&](const std::string& temp) {
                                    std::ofstream(temp) << "new";
                                    REQUIRE(fs::exists(temp));
                                    removeLiveTemporaries();
                                    CHECK_FALSE(fs::exists(temp));
                                }),
                    Error);
    CHECK_FALSE(fs::exists(first));
    CHECK(slurp(dir.file("kept.txt")) == "old");
    CHECK(dir.entries() == 1);
    // A file renamed over its target is no longer the handler's to remove.
    OutputBatch done;
    done.stage(dir.file("done.txt"), [](const std::string& temp) { std::ofstream(temp) << "done"; });
    done.commit();
    removeLiveTemporaries();
    CHECK(slurp(dir.file("done.txt")) == "done");
}

TEST_CASE("atomic write: a link is followed and a replaced file keeps its mode", "[io]") {
    TempDir dir;
    const std::string real = dir.file("real.stl");
    std::ofstream(real) << "old";
    fs::create_directories(dir.path / "sub");
    // link.stl -> sub/hop.stl -> ../real.stl: each link's text is read from its own folder.
    fs::create_symlink("../real.stl", dir.path / "sub" / "hop.stl");
    fs::create_symlink("sub/hop.stl", dir.path / "link.stl");
    checkWritable(dir.file("link.stl"));
    writeStreamAtomically(dir.file("link.stl"), [](std::ostream& out) { out << "new"; });
    CHECK(fs::is_symlink(dir.path / "link.stl"));
    CHECK(fs::is_symlink(dir.path / "sub" / "hop.stl"));
    CHECK(slurp(real) == "new");
    CHECK(dir.entries() == 3);
    // A link to a missing file makes the file.
    fs::create_symlink("made.stl", dir.path / "dangling.stl");
    writeStreamAtomically(dir.file("dangling.stl"), [](std::ostream& out) { out << "made"; });
    CHECK(fs::is_symlink(dir.path / "dangling.stl"));
    CHECK(slurp(dir.file("made.stl")) == "made");
    // Links in a loop, or to a folder, are refused.
    fs::create_symlink("loop2", dir.path / "loop1");
    fs::create_symlink("loop1", dir.path / "loop2");
    CHECK_THROWS_WITH(writeStreamAtomically(dir.file("loop1"), [](std::ostream&) {}),
                      Catch::Matchers::Contains("too many levels of symbolic links"));
    fs::create_symlink("sub", dir.path / "folder.stl");
    CHECK_THROWS_WITH(checkWritable(dir.file("folder.stl")), Catch::Matchers::Contains("it is a folder"));
    CHECK(fs::is_symlink(dir.path / "folder.stl"));

    // The mode of the file replaced, whatever the umask: 022 would take 0664's group write.
    const ::mode_t umaskWas = ::umask(022);
    for (const fs::perms mode : {fs::perms(0600), fs::perms(0664), fs::perms(0751)}) {
        INFO(std::oct << int(mode));
        fs::permissions(real, mode);
        writeFileAtomically(dir.file("link.stl"), [&](const std::string& temp) {
            // While written, no one may read it who may not read the file (its writer aside).
            CHECK((fs::status(temp).permissions() & ~(mode | fs::perms(0600))) == fs::perms::none);
            std::ofstream(temp) << "again";
        });
        CHECK(fs::status(real).permissions() == mode);
        CHECK(slurp(real) == "again");
    }
    ::umask(umaskWas);
}

TEST_CASE("atomic write: a replaced file keeps its owner and group where root writes it", "[io]") {
    if (::geteuid() != 0) {
        WARN("not root: a user cannot give a file to another, skipped");
        return;
    }
    TempDir dir;
    const std::string file = dir.file("theirs.json");
    std::ofstream(file) << "old";
    REQUIRE(::chown(file.c_str(), 65534, 65533) == 0);
    REQUIRE(::chmod(file.c_str(), 02640) == 0);  // a change of owner clears set-ID bits
    writeStreamAtomically(file, [](std::ostream& out) { out << "new"; });
    struct stat st {};
    REQUIRE(::stat(file.c_str(), &st) == 0);
    CHECK(st.st_uid == 65534);
    CHECK(st.st_gid == 65533);
    CHECK((st.st_mode & 07777) == 02640);
    CHECK(slurp(file) == "new");
}

TEST_CASE("atomic write: a FIFO or a device is written in place, a socket refused", "[io]") {
    TempDir dir;
    const std::string fifo = dir.file("pipe.json");
    REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
    // The reader's end is open before the write (without blocking), so the write does not wait.
    const int reader = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
    REQUIRE(reader >= 0);
    checkWritable(fifo);
    writeStreamAtomically(fifo, [](std::ostream& out) { out << "through the pipe"; });
    char got[64] = {};
    const ::ssize_t n = ::read(reader, got, sizeof got);
    ::close(reader);
    CHECK(std::string(got, std::size_t(std::max<::ssize_t>(n, 0))) == "through the pipe");
    CHECK(fs::is_fifo(fifo));
    CHECK(dir.entries() == 1);

    // A device node of its own (the null device's numbers), never the system's /dev/null; making
    // one takes root.
    const std::string null = dir.file("null.json");
    if (::mknod(null.c_str(), S_IFCHR | 0666, ::makedev(1, 3)) == 0) {
        fs::create_symlink("null.json", dir.path / "to-null.json");
        for (const std::string& target : {null, dir.file("to-null.json")}) {
            INFO(target);
            checkWritable(target);
            writeStreamAtomically(target, [](std::ostream& out) { out << "gone"; });
            CHECK(fs::is_character_file(null));
        }
        CHECK(fs::is_symlink(dir.path / "to-null.json"));
        // A write the device fails (the full device's numbers) leaves the device: libpng's own
        // file writer removes its file when a write fails.
        const std::string full = dir.file("full.png");
        REQUIRE(::mknod(full.c_str(), S_IFCHR | 0666, ::makedev(1, 7)) == 0);
        CHECK_THROWS_AS(writePng(full, Image{4, 4, std::vector<std::uint8_t>(48, 128)}), Error);
        CHECK_THROWS_AS(writeStreamAtomically(full, [](std::ostream& out) { out << "x"; }), Error);
        CHECK(fs::is_character_file(full));
        CHECK(dir.entries() == 4);
    } else {
        WARN("cannot make a device node (not root): the device case skipped");
    }

    const std::string socketPath = dir.file("sock.json");
    const int sock = ::socket(AF_UNIX, SOCK_STREAM, 0);
    REQUIRE(sock >= 0);
    ::sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::strncpy(address.sun_path, socketPath.c_str(), sizeof address.sun_path - 1);
    REQUIRE(::bind(sock, reinterpret_cast<const ::sockaddr*>(&address), sizeof address) == 0);
    CHECK_THROWS_WITH(checkWritable(socketPath), Catch::Matchers::Contains("it is a socket"));
    CHECK_THROWS_WITH(writeStreamAtomically(socketPath, [](std::ostream& out) { out << "x"; }),
                      Catch::Matchers::Contains("it is a socket"));
    ::close(sock);
    CHECK(fs::is_socket(socketPath));
}

TEST_CASE("atomic write: an open descriptor is written in place, whatever it holds and whatever its name",
          "[io]") {
    TempDir dir;
    // A pipe's entry in /proc/self/fd reads "pipe:[N]", a name no path reaches: the target is
    // what the system opens, as /dev/stdout on a pipe is.
    int ends[2];
    REQUIRE(::pipe(ends) == 0);
    for (const std::string& target : {"/proc/self/fd/" + std::to_string(ends[1]), "/dev/fd/" + std::to_string(ends[1])}) {
        INFO(target);
        CHECK(writtenInPlace(target));
        CHECK(takesFormat(target, ".json"));
        checkWritable(target);
        writeStreamAtomically(target, [](std::ostream& out) { out << "down the pipe"; });
        char got[64] = {};
        const ::ssize_t n = ::read(ends[0], got, sizeof got);
        CHECK(std::string(got, std::size_t(std::max<::ssize_t>(n, 0))) == "down the pipe");
    }
    ::close(ends[0]);
    ::close(ends[1]);
    // A regular file the descriptor holds (`> report.json`) stays that file: no temporary file, no
    // rename, and the descriptor's file is the one written.
    const std::string file = dir.file("report.json");
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    REQUIRE(fd >= 0);
    struct stat before {};
    REQUIRE(::stat(file.c_str(), &before) == 0);
    const std::string target = "/proc/self/fd/" + std::to_string(fd);
    CHECK(writtenInPlace(target));
    writeStreamAtomically(target, [](std::ostream& out) { out << "{}"; });
    struct stat after {};
    REQUIRE(::fstat(fd, &after) == 0);
    ::close(fd);
    CHECK(after.st_ino == before.st_ino);
    CHECK(after.st_nlink == 1);
    CHECK(after.st_size == 2);
    CHECK(dir.entries() == 1);
    // Named files are not: a FIFO is, a regular file or a missing one is not, by any name.
    const std::string fifo = dir.file("pipe");
    REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
    CHECK(writtenInPlace(fifo));
    CHECK(takesFormat(fifo, ".png"));
    CHECK_FALSE(writtenInPlace(file));
    CHECK_FALSE(takesFormat(file, ".png"));
    CHECK(takesFormat(dir.file("PART.PNG"), ".png"));
    CHECK_FALSE(writtenInPlace(dir.file("missing.json")));
    CHECK_FALSE(writtenInPlace(dir.file("missing/r.json")));
    // Two outputs in one FIFO, or in one device, follow each other; in one regular file they clash.
    CHECK_NOTHROW(checkSeparateFiles({}, {{"-o", fifo}, {"--report", fifo}}));
    CHECK_THROWS_WITH(checkSeparateFiles({}, {{"-o", file}, {"--report", file}}),
                      Catch::Matchers::Contains("are the same file"));
}

TEST_CASE("atomic write: a name as long as the folder takes gets a temporary file within the limit", "[io]") {
    // Linux file systems take names of up to 255 bytes; the temporary file's name adds a dot and
    // ".tmpPID_N" to the target's, and is cut to fit.
    TempDir dir;
    for (const std::string& name : {std::string(246, 'a') + ".stl", std::string(251, 'a') + ".stl"}) {
        INFO(name.size() << " bytes");
        const std::string target = dir.file(name);
        checkWritable(target);
        std::string temp;
        writeFileAtomically(target, [&](const std::string& path) {
            temp = fs::path(path).filename().string();
            std::ofstream(path) << "mesh";
        });
        CHECK(slurp(target) == "mesh");
        CHECK(temp.size() <= 255);
        CHECK(temp.rfind("." + std::string(200, 'a'), 0) == 0);
        CHECK(dir.entries() == 1);
        fs::remove(target);
    }
    // A cut falls between characters, never inside one: names of three-byte characters after
    // 0 to 5 one-byte ones put the cut at each place in a character.
    const std::string euro = "\xe2\x82\xac";
    for (std::size_t ascii = 0; ascii < 6; ++ascii) {
        std::string name(ascii, 'a');
        while (name.size() + euro.size() + 4 <= 255) name += euro;
        name += ".stl";
        std::string temp;
        writeFileAtomically(dir.file(name), [&](const std::string& path) {
            temp = fs::path(path).filename().string();
            std::ofstream(path) << "mesh";
        });
        INFO(temp);
        CHECK(temp.size() <= 255);
        const std::size_t end = temp.rfind(".tmp");
        REQUIRE(end != std::string::npos);
        REQUIRE(temp.substr(0, 1 + ascii) == "." + std::string(ascii, 'a'));
        const std::string kept = temp.substr(1 + ascii, end - 1 - ascii);
        CHECK(kept.size() % euro.size() == 0);
        CHECK(name.rfind(std::string(ascii, 'a') + kept, 0) == 0);
        CHECK(slurp(dir.file(name)) == "mesh");
        fs::remove(dir.file(name));
    }
}

TEST_CASE("separate files: an output that is an input or another output is refused, naming both", "[io]") {
    TempDir dir;
    const std::string program = dir.file("part.ngc");
    std::ofstream(program) << "G0 X0";
    fs::create_symlink("part.ngc", dir.path / "link.json");
    fs::create_hard_link(program, dir.path / "hard.json");
    fs::create_directories(dir.path / "sub");
    const std::vector<NamedFile> inputs{{"INPUTS", program}, {"--design", ""}};
    // The same file through a symbolic link, a hard link, or another spelling of its path.
    for (const std::string& out : {dir.file("link.json"), dir.file("hard.json"), dir.file("sub/../part.ngc")}) {
        INFO(out);
        CHECK_THROWS_WITH(checkSeparateFiles(inputs, {{"-o", dir.file("part.stl")}, {"--report", out}}),
                          "--report '" + out + "' is the same file as INPUTS '" + program +
                              "', which the job reads: give the output another name");
    }
    // Two outputs not made yet: the same path, or a link to a missing file and that file.
    fs::create_symlink("table.csv", dir.path / "plot.png");
    for (const auto& [a, b] : {std::pair<std::string, std::string>{dir.file("out.ply"), dir.file("sub/../out.ply")},
                               {dir.file("table.csv"), dir.file("plot.png")}}) {
        INFO(a << " " << b);
        CHECK_THROWS_WITH(checkSeparateFiles(inputs, {{"--csv", a}, {"--vdb", ""}, {"--plot", b}}),
                          "--csv '" + a + "' and --plot '" + b + "' are the same file: give each output a name of its own");
    }
    // Files of their own, and options not given, pass.
    CHECK_NOTHROW(checkSeparateFiles(inputs, {{"-o", dir.file("part.stl")}, {"--png", ""}, {"--report", dir.file("r.json")}}));
    CHECK_NOTHROW(checkSeparateFiles({{"INPUTS", program}, {"INPUTS", program}}, {{"-o", ""}}));
    CHECK(dir.entries() == 5);
}
