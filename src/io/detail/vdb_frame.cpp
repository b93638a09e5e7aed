#include "vdb_frame.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <limits>

#include "binary.h"

namespace dexelmill::detail {

namespace {

/// The int64 every OpenVDB file begins with: "VDB " little-endian.
constexpr std::uint64_t kMagic = 0x56444220;
/// The format versions whose framing is checked. 222 moved the compression flags from the header
/// to each grid; 223 (Blosc) and 224 (multi-pass I/O, OpenVDB 10's) changed only the trees. Each
/// was verified by reading with OpenVDB a file written as 224 and relabelled.
constexpr std::uint32_t kFirstCheckedVersion = 222;
constexpr std::uint32_t kLastCheckedVersion = 224;
/// The header's UUID: 36 ASCII characters, 8-4-4-4-12 hex digits with dashes.
constexpr std::size_t kUuidChars = 36;
/// The metadata types OpenVDB registers whose value has a fixed size: it reads that many bytes,
/// whatever length the file gives the value. (Names and sizes as OpenVDB 10 registers them.)
struct FixedType {
    const char* name;
    std::uint32_t bytes;
};
constexpr std::array<FixedType, 16> kFixedTypes = {{{"bool", 1},   {"int32", 4},  {"int64", 8},  {"float", 4},
                                                    {"double", 8}, {"vec2i", 8},  {"vec2s", 8},  {"vec2d", 16},
                                                    {"vec3i", 12}, {"vec3s", 12}, {"vec3d", 24}, {"vec4i", 16},
                                                    {"vec4s", 16}, {"vec4d", 32}, {"mat4s", 64}, {"mat4d", 128}}};
/// The type of the metadata OpenVDB writes with a grid for reading it in parts later.
constexpr const char* kDelayedLoadType = "__delayedload";
/// The longest of the type names above: a longer one is skipped unread.
constexpr std::size_t kLongestKnownType = 13;
/// The bytes of each leaf's entry in the "__delayedload" value's mask and in its compressed sizes.
constexpr std::uint64_t kMaskBytes = 1;
constexpr std::uint64_t kCompressedSizeBytes = 8;
/// The size of the compressed sizes that says there are none.
constexpr std::uint32_t kNoCompressedSizes = 0xffffffffu;
/// A Blosc block's header: 16 bytes, with the uint32 sizes of the data uncompressed at byte 4 and
/// of the whole block compressed at byte 12.
constexpr std::uint64_t kBloscHeaderBytes = 16;
constexpr std::uint64_t kBloscUncompressedAt = 4;
constexpr std::uint64_t kBloscCompressedAt = 12;
/// OpenVDB pads an array shorter than this with zeros to this many bytes before Blosc compresses
/// it (arrays of 48 bytes or fewer it stores raw): the header then gives the padded size. (A grid
/// of 8 leaves: its 64 bytes of compressed sizes are compressed as 128.)
constexpr std::uint64_t kBloscPadBytes = 128;

/// The most bytes the check reads past rather than seeking over: about a stream buffer's worth.
constexpr std::uint64_t kMostBytesSkippedByReading = 4096;

/// The check stops and leaves the file to OpenVDB: it ends inside a fixed-size field, or the
/// stream fails.
struct Unchecked {};

/// A length or offset the file cannot hold, described.
struct Damaged {
    std::string what;
    bool cutShort;
};

/// Reads the file at an offset of its own, never past `size`.
class Cursor {
public:
    Cursor(std::istream& in, std::uint64_t size) : in_(in), size_(size) {}

    std::uint64_t at() const { return at_; }
    std::uint64_t left() const { return size_ - at_; }
    std::uint64_t size() const { return size_; }
    void seek(std::uint64_t at) { at_ = at; }
    /// Moves past `n` bytes; n <= left().
    void skip(std::uint64_t n) { at_ += n; }

    std::uint32_t u32() {
        char b[4];
        fill(b, sizeof b);
        return binary::getU32(b);
    }
    std::int64_t i64() {
        char b[8];
        fill(b, sizeof b);
        const std::uint64_t v = std::uint64_t(binary::getU32(b)) | std::uint64_t(binary::getU32(b + 4)) << 32;
        std::int64_t s;
        std::memcpy(&s, &v, sizeof s);
        return s;
    }
    /// The next `n` bytes; n small.
    std::string text(std::size_t n) {
        std::string s(n, '\0');
        fill(s.data(), n);
        return s;
    }

private:
    void fill(char* p, std::size_t n) {
        if (n > left()) throw Unchecked{};
        // A seek empties the stream's buffer: reads in a row go without, and a short skip reads past.
        if (at_ > streamAt_ && at_ - streamAt_ <= kMostBytesSkippedByReading)
            in_.ignore(std::streamsize(at_ - streamAt_));
        else if (at_ != streamAt_)
            in_.seekg(std::streamoff(at_));
        in_.read(p, std::streamsize(n));
        if (!in_) throw Unchecked{};
        at_ += n;
        streamAt_ = at_;
    }

    std::istream& in_;
    std::uint64_t size_;
    std::uint64_t at_ = 0;
    /// Where the stream stands, if known.
    std::uint64_t streamAt_ = std::numeric_limits<std::uint64_t>::max();
};

std::string str(std::uint64_t v) { return std::to_string(v); }

/// What a length belongs to, named only in a message (a file's metadata may hold millions of
/// entries): a metadata entry, or a grid's descriptor where `entry` is 0.
struct Owner {
    std::uint32_t grid;   ///< from 1; 0 for the file's own metadata
    std::uint32_t entry;  ///< from 1

    std::string name() const {
        if (entry == 0) return "grid " + str(grid);
        const std::string map = grid == 0 ? "the file's metadata" : "grid " + str(grid) + "'s metadata";
        return "entry " + str(entry) + " of " + map;
    }
};

/// Checks that the bytes after the uint32 length `n` at byte `at` of `field` ("the name") of
/// `owner` hold that many.
void checkFits(const Cursor& c, std::uint32_t n, std::uint64_t at, const char* field, const Owner& owner) {
    if (n > c.left())
        throw Damaged{"the length " + str(n) + " of " + field + " of " + owner.name() + ", at byte " + str(at) +
                          ", is more than the " + str(c.left()) + " bytes after it",
                      false};
}

/// Reads the uint32 length of `field` of `owner` and checks that the bytes after it hold that many.
std::uint32_t length(Cursor& c, const char* field, const Owner& owner) {
    const std::uint64_t at = c.at();
    const std::uint32_t n = c.u32();
    checkFits(c, n, at, field, owner);
    return n;
}

/// The value, `valueBytes` long, of OpenVDB's "__delayedload" metadata: a uint32 count of leaves,
/// then a byte each (a mask) and an int64 each (compressed sizes; none where the block's uint32 size
/// is all ones), each block a uint32 size and that many bytes of Blosc, or 0 and the values raw.
/// OpenVDB sizes its arrays by the count and by the Blosc header's uncompressed size, not by the
/// value's length: each must agree with the others, the header's size padded as kBloscPadBytes says.
void checkDelayedLoad(Cursor& c, std::uint32_t valueBytes, const Owner& owner) {
    if (valueBytes == 0) return;
    const std::uint64_t end = c.at() + valueBytes;
    const auto past = [&](std::uint64_t bytes) { return bytes > end - std::min(end, c.at()); };
    const auto damaged = [&](const std::string& what, std::uint64_t at) {
        return Damaged{what + ", at byte " + str(at) + ", is more than the value of " + owner.name() + " holds (" +
                           str(valueBytes) + " bytes)",
                       false};
    };
    if (past(sizeof(std::uint32_t))) throw damaged("the leaf count", c.at());
    const std::uint64_t leaves = c.u32();
    for (const std::uint64_t elementBytes : {kMaskBytes, kCompressedSizeBytes}) {
        const std::string array = elementBytes == kMaskBytes ? "the mask" : "the list of compressed sizes";
        const std::uint64_t arrayBytes = leaves * elementBytes;
        const std::uint64_t at = c.at();
        if (past(sizeof(std::uint32_t))) throw damaged("the size of " + array, at);
        const std::uint32_t bytes = c.u32();
        if (elementBytes == kCompressedSizeBytes && bytes == kNoCompressedSizes) break;
        if (bytes == 0) {
            if (past(arrayBytes))
                throw damaged(array + " of " + str(leaves) + " leaves stored raw (" + str(arrayBytes) +
                                  " bytes)",
                              at);
            c.skip(arrayBytes);
            continue;
        }
        if (bytes < kBloscHeaderBytes || past(bytes)) throw damaged("the size " + str(bytes) + " of " + array, at);
        const std::uint64_t header = c.at();
        c.skip(kBloscUncompressedAt);
        const std::uint64_t uncompressed = c.u32();
        c.skip(kBloscCompressedAt - kBloscUncompressedAt - sizeof(std::uint32_t));
        const std::uint64_t compressed = c.u32();
        const bool padded = arrayBytes < kBloscPadBytes && uncompressed == kBloscPadBytes;
        if ((uncompressed != arrayBytes && !padded) || compressed != bytes)
            throw Damaged{"the Blosc header of " + array + " in the value of " + owner.name() + ", at byte " +
                              str(header) + ", holds " + str(uncompressed) + " bytes compressed to " + str(compressed) +
                              ", not the " + str(arrayBytes) + " of " + str(leaves) +
                              " leaves compressed to " + str(bytes),
                          false};
        c.seek(header + bytes);
    }
    c.seek(end);
}

/// The metadata map (MetaMap) of grid `grid`, from 1, or the file's where 0: a uint32 count, then
/// per entry a name, a type name and a value, each a uint32 length and that many bytes (a value of
/// a fixed-size type: its type's size).
void checkMetadata(Cursor& c, std::uint32_t grid) {
    // A count past what the file holds is not judged: OpenVDB reserves nothing for it, and the
    // entries then run into bytes that are not, or past the file's end.
    const std::uint32_t entries = c.u32();
    for (std::uint32_t e = 1; e <= entries; ++e) {
        const Owner entry{grid, e};
        const std::uint32_t nameLength = length(c, "the name", entry);
        c.skip(nameLength);
        const std::uint32_t typeLength = length(c, "the type name", entry);
        const std::string type = typeLength <= kLongestKnownType ? c.text(typeLength) : "";
        if (typeLength > kLongestKnownType) c.skip(typeLength);
        const std::uint64_t valueAt = c.at();
        const std::uint32_t valueBytes = c.u32();
        const auto fixed = std::find_if(kFixedTypes.begin(), kFixedTypes.end(),
                                        [&](const FixedType& t) { return type == t.name; });
        if (fixed != kFixedTypes.end()) {
            if (fixed->bytes > c.left()) throw Unchecked{};
            c.skip(fixed->bytes);
        } else {
            checkFits(c, valueBytes, valueAt, "the value", entry);
            if (type == kDelayedLoadType)
                checkDelayedLoad(c, valueBytes, entry);
            else
                c.skip(valueBytes);
        }
        // OpenVDB refuses an entry without a name once it has read it: a run of zero bytes ends there.
        if (nameLength == 0) throw Unchecked{};
    }
}

/// Whether `uuid` is 8-4-4-4-12 hex digits with dashes.
bool isUuid(const std::string& uuid) {
    for (std::size_t i = 0; i < uuid.size(); ++i) {
        const bool dash = i == 8 || i == 13 || i == 18 || i == 23;
        const char ch = uuid[i];
        const bool hex = (ch >= '0' && ch <= '9') || (ch >= 'a' && ch <= 'f') || (ch >= 'A' && ch <= 'F');
        if (dash ? ch != '-' : !hex) return false;
    }
    return true;
}

/// The descriptor of grid `g` (its name, type name and instance parent's name, then the int64
/// offsets of the grid, of its voxel blocks and of its end), where the cursor stands, and the
/// grid's compression flags and metadata. Leaves the cursor at the next descriptor; returns false
/// where that cannot be found (a file without offsets).
bool checkGrid(Cursor& c, std::uint32_t g, bool hasOffsets) {
    const std::string grid = "grid " + str(g);
    const Owner descriptor{g, 0};
    c.skip(length(c, "the name", descriptor));
    c.skip(length(c, "the type name", descriptor));
    c.skip(length(c, "the instance parent's name", descriptor));
    const std::uint64_t offsetsAt = c.at();
    const std::int64_t gridPos = c.i64();
    const std::int64_t blockPos = c.i64();
    const std::int64_t endPos = c.i64();
    // OpenVDB writes the grid right after its descriptor; its stream reader reads it from there.
    const std::int64_t gridStart = std::int64_t(c.at());
    if (hasOffsets && (gridPos != gridStart || blockPos < gridPos || endPos < blockPos))
        throw Damaged{"the offsets of " + grid + " at byte " + str(offsetsAt) + " (grid " + std::to_string(gridPos) +
                          ", blocks " + std::to_string(blockPos) + ", end " + std::to_string(endPos) +
                          ") do not run in order from byte " + str(std::uint64_t(gridStart)) +
                          ", where its descriptor ends",
                      false};
    // A grid that ends past the file's end, its offsets otherwise in order, says the file stops
    // short: that, rather than any length its metadata then runs past the end with.
    const bool cut = hasOffsets && std::uint64_t(endPos) > c.size();
    const Damaged pastEnd{grid + " ends, by its offsets at byte " + str(offsetsAt) + ", at byte " +
                              std::to_string(endPos) + ", past the file's end at byte " + str(c.size()),
                          true};
    try {
        c.u32();  // the grid's compression flags
        checkMetadata(c, g);
    } catch (...) {
        if (cut) throw pastEnd;
        throw;
    }
    if (cut) throw pastEnd;
    if (!hasOffsets) return false;
    if (c.at() > std::uint64_t(blockPos))
        throw Damaged{"the metadata of " + grid + " ends at byte " + str(c.at()) + ", past the offset " +
                          std::to_string(blockPos) + " of its blocks",
                      false};
    c.seek(std::uint64_t(endPos));
    return true;
}

}  // namespace

std::optional<VdbFramingProblem> vdbFramingProblem(std::istream& in, std::uint64_t size) {
    Cursor c(in, size);
    try {
        if (std::uint64_t(c.i64()) != kMagic) return std::nullopt;
        const std::uint32_t version = c.u32();
        if (version < kFirstCheckedVersion || version > kLastCheckedVersion) return std::nullopt;
        c.u32();  // the library's major version
        c.u32();  // and minor version
        const bool hasOffsets = c.text(1)[0] != 0;
        if (!isUuid(c.text(kUuidChars))) return std::nullopt;
        checkMetadata(c, 0);
        // OpenVDB reads the grid count as an int32: a negative one means no grid.
        const std::uint32_t grids = c.u32();
        if (grids <= std::uint32_t(INT32_MAX))
            for (std::uint32_t g = 1; g <= grids; ++g)
                if (!checkGrid(c, g, hasOffsets)) break;
    } catch (const Unchecked&) {
        return std::nullopt;
    } catch (const Damaged& d) {
        return VdbFramingProblem{d.what, d.cutShort};
    }
    return std::nullopt;
}

}  // namespace dexelmill::detail
