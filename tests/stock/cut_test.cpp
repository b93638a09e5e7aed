// The cutting loop: consistency of the three dexel families after random programs, determinism
// across thread counts, collision reports, statistics.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <random>
#include <string>

#include <tbb/global_control.h>

#include "dexelmill/error.h"
#include "dexelmill/stock/cut.h"
#include "dexelmill/tool/builders.h"
#include "support/slot_job.h"

using namespace dexelmill;

namespace {

const Box kStockBox{Vec3(0, 0, 0), Vec3(20, 20, 10)};

ToolTable testTools() {
    ToolTable t;
    t.emplace(1, flatEndMill(4.0, {15.0, 25.0}));
    t.emplace(2, ballEndMill(3.0, {15.0, 25.0}));
    t.emplace(3, bullNoseEndMill(5.0, 1.0, {15.0, 25.0}));
    t.emplace(4, chamferMill(0.0, 0.6, 6.0, {15.0, 25.0}));
    return t;
}

/// A random program over the stock: feeds, ramps, plunges and a few tilted axes, with the tips
/// between 5 and 11 mm high (the stock is 10 mm high).
ToolPath randomProgram(std::uint64_t seed, int moves) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> xy(-2.0, 22.0), z(5.0, 11.0), unit(0.0, 1.0);
    ToolPath path;
    path.files.push_back("random.nc");
    Vec3 at(xy(rng), xy(rng), z(rng));
    int tool = 1;
    for (int i = 0; i < moves; ++i) {
        if (i % 50 == 0) tool = 1 + int(rng() % 4);
        Move m;
        m.start = at;
        const double r = unit(rng);
        if (r < 0.1) m.end = Vec3(at.x, at.y, z(rng));                          // plunge or retract
        else if (r < 0.5) m.end = Vec3(xy(rng), xy(rng), at.z);                 // horizontal
        else m.end = Vec3(xy(rng), xy(rng), z(rng));                            // ramp
        m.axis = unit(rng) < 0.15 ? glm::normalize(Vec3(unit(rng) - 0.5, unit(rng) - 0.5, 2.0)) : Vec3(0, 0, 1);
        m.tool = tool;
        m.source = SourceRef{0, i + 1};
        path.moves.push_back(m);
        at = m.end;
    }
    return path;
}

std::size_t segmentCount(const TriDexelStock& s, Axis a) {
    const DexelFamily& f = s.family(a);
    std::size_t n = 0;
    for (int ic = 0; ic < f.nc(); ++ic)
        for (int ib = 0; ib < f.nb(); ++ib) n += f.segments(ib, ic).size;
    return n;
}

bool sameStock(const TriDexelStock& a, const TriDexelStock& b) {
    for (int ax = 0; ax < 3; ++ax) {
        const DexelFamily& fa = a.family(axisFromIndex(ax));
        const DexelFamily& fb = b.family(axisFromIndex(ax));
        for (int ic = 0; ic < fa.nc(); ++ic) {
            for (int ib = 0; ib < fa.nb(); ++ib) {
                const SegmentSpan sa = fa.segments(ib, ic), sb = fb.segments(ib, ic);
                if (sa.size != sb.size) return false;
                for (std::size_t k = 0; k < sa.size; ++k)
                    if (sa[k].lo != sb[k].lo || sa[k].hi != sb[k].hi) return false;
            }
        }
    }
    return true;
}

}  // namespace

TEST_CASE("cut: after a random program the three families agree", "[stock][cut]") {
    const double h = 0.25;
    TriDexelStock stock = TriDexelStock::fromBox(kStockBox, h);
    const ToolPath path = randomProgram(7, 300);
    const CutResult res = cutStock(stock, path, testTools());
    REQUIRE(res.removedVolume > 100.0);  // the program does cut

    // Every lattice point gets the same answer from its three dexels.
    const Lattice& l = stock.lattice();
    std::size_t inside = 0, mismatches = 0;
    for (int k = 0; k < l.n[2]; ++k)
        for (int j = 0; j < l.n[1]; ++j)
            for (int i = 0; i < l.n[0]; ++i) {
                const bool x = stock.inside(Axis::X, i, j, k), y = stock.inside(Axis::Y, i, j, k),
                           z = stock.inside(Axis::Z, i, j, k);
                inside += x;
                mismatches += (x != y) || (y != z);
            }
    INFO(inside << " of " << l.pointCount() << " lattice points inside");
    CHECK(mismatches == 0);
    CHECK(inside > 0);
    CHECK(double(inside) < l.pointCount());

    // Volumes. Each family's volume (h^2 times its segment lengths) against the lattice points
    // inside, counted above through inside(): a segment holding k points has a length within h of
    // k h, so |V_a - N h^3| <= h^3 S_a for S_a segments. That is h^2 per dexel end, O(h^2) in the
    // lattice's own units; the bound between two families follows. Over the whole part it is O(h)
    // times the area of the faces parallel to a family, and no better: a floor moves every x and y
    // dexel crossing it by the same offset from the lattice (seeds 7 to 9 at h = 0.5, 0.25, 0.125
    // give x-z gaps of 3.6 to 10.6 mm^3 with no steady fall, while z, which holds floors exactly,
    // changes by under 0.6 mm^3).
    const double pointVolume = double(inside) * h * h * h;
    const double v[3] = {stock.volume(Axis::X), stock.volume(Axis::Y), stock.volume(Axis::Z)};
    for (int a = 0; a < 3; ++a) {
        const double segs = double(segmentCount(stock, axisFromIndex(a)));
        INFO("V" << "xyz"[a] << " = " << v[a] << ", lattice points " << pointVolume << ", segments " << segs);
        CHECK(std::abs(v[a] - pointVolume) <= h * h * h * segs);
    }
    // The removed volumes add up to what the families lost (mean over the three).
    const double before = kStockBox.volume();
    CHECK(before - (v[0] + v[1] + v[2]) / 3.0 == Approx(res.removedVolume).epsilon(1e-9));
}

TEST_CASE("cut: 1 and N threads give identical results bit for bit", "[stock][cut]") {
    // Up to 4 workers even on a 2-core machine, so that tiles really are shared out unevenly.
    const tbb::global_control allow(tbb::global_control::max_allowed_parallelism, 4);
    const ToolTable tools = testTools();
    for (std::uint64_t seed : {11, 12}) {
        const ToolPath path = randomProgram(seed, 250);
        TriDexelStock serial = TriDexelStock::fromBox(kStockBox, 0.3);
        CutOptions one;
        one.threads = 1;
        const CutResult a = cutStock(serial, path, tools, one);
        REQUIRE(a.removedVolume > 0.0);
        for (int threads : {2, 4}) {
            for (std::size_t batch : {std::size_t(0), std::size_t(7)}) {
                INFO("seed " << seed << ", " << threads << " threads, batch " << batch);
                TriDexelStock parallel = TriDexelStock::fromBox(kStockBox, 0.3);
                CutOptions many;
                many.threads = threads;
                many.batchMoves = batch;
                const CutResult b = cutStock(parallel, path, tools, many);
                CHECK(sameStock(serial, parallel));
                REQUIRE(b.moves.size() == a.moves.size());
                bool same = b.bounded == a.bounded && b.visited == a.visited && b.changed == a.changed && b.removedVolume == a.removedVolume &&
                            b.collisions.size() == a.collisions.size();
                for (std::size_t i = 0; i < a.moves.size(); ++i)
                    same = same && b.moves[i].visited == a.moves[i].visited &&
                           b.moves[i].changed == a.moves[i].changed && b.moves[i].removed == a.moves[i].removed &&
                           b.moves[i].shankVolume == a.moves[i].shankVolume;
                CHECK(same);
            }
        }
    }
}

TEST_CASE("cut: batches ended by the linear-node budget give the same stock bit for bit", "[stock][cut][turning]") {
    // Six feed moves across the block with the axis turning a degree each way: a flat end's
    // sweeps take linear nodes (TurningSweep, note h), and each can keep a tree of them.
    const ToolTable tools = testTools();
    ToolPath path;
    path.files.push_back("turning.nc");
    const double tilt = std::acos(-1.0) / 180.0;
    for (int i = 0; i < 6; ++i) {
        Move m;
        m.start = Vec3(i % 2 == 0 ? -3.0 : 23.0, 2.0 + 3.0 * i, 8.0);
        m.end = Vec3(i % 2 == 0 ? 23.0 : -3.0, 3.0 + 3.0 * i, 7.5);
        m.startAxis = Vec3(std::sin(-tilt), 0.0, std::cos(tilt));
        m.axis = Vec3(std::sin(tilt), 0.0, std::cos(tilt));
        m.tool = 1;
        m.source = SourceRef{0, i + 1};
        path.moves.push_back(m);
    }
    const std::map<int, ToolRegions> regions = toolRegions(path, tools);
    std::vector<std::size_t> bounds;
    for (const Move& m : path.moves) bounds.push_back(MoveGeometry(regions.at(1), m).linearNodeBound());
    REQUIRE(std::all_of(bounds.begin(), bounds.end(), [](std::size_t b) { return b > 0; }));

    const auto cut = [&](std::size_t budget, std::vector<std::size_t>& ends) {
        TurningSweep::setLinearNodeBudget(budget);
        TriDexelStock stock = TriDexelStock::fromBox(kStockBox, 0.3);
        CutOptions opt;
        opt.threads = 2;
        opt.progress = [&](std::size_t done, std::size_t) { ends.push_back(done); };
        const CutResult r = cutStock(stock, path, tools, opt);
        TurningSweep::setLinearNodeBudget(kDefaultLinearNodeBudget);
        return std::make_pair(std::move(stock), r);
    };
    std::vector<std::size_t> wholeEnds, pairEnds, singleEnds;
    const std::size_t whole = std::accumulate(bounds.begin(), bounds.end(), std::size_t(0));
    const auto [wholeStock, wholeResult] = cut(whole, wholeEnds);
    // A budget that holds the first two moves' trees and not the third's: batches of two (the
    // moves' trees are alike).
    const auto [pairStock, pairResult] = cut(bounds[0] + bounds[1], pairEnds);
    const auto [singleStock, singleResult] = cut(0, singleEnds);
    CHECK(wholeEnds == std::vector<std::size_t>{6});
    CHECK(pairEnds == std::vector<std::size_t>{2, 4, 6});
    CHECK(singleEnds == std::vector<std::size_t>{1, 2, 3, 4, 5, 6});
    REQUIRE(wholeResult.removedVolume > 100.0);
    CHECK(sameStock(wholeStock, pairStock));
    CHECK(sameStock(wholeStock, singleStock));
    CHECK(pairResult.removedVolume == wholeResult.removedVolume);
    CHECK(singleResult.removedVolume == wholeResult.removedVolume);
    for (std::size_t i = 0; i < path.moves.size(); ++i) {
        CHECK(pairResult.moves[i].removed == wholeResult.moves[i].removed);
        CHECK(singleResult.moves[i].changed == wholeResult.moves[i].changed);
    }
}

TEST_CASE("cut: a move that turns far is swept in pieces, its statistics its own, in any batch and thread",
          "[stock][cut][turning]") {
    // A fixed-axis feed, a move turning 5 degrees (one piece), one turning 25 (three), a rapid
    // turning 60 (swept with its end axis: whole) and a feed turning 95 (ten), in the block. The
    // tools have shanks: a move in pieces is swept first in its flutes' pieces, then its shank's.
    const ToolTable tools = testTools();
    ToolPath path;
    path.files.push_back("pieces.nc");
    const double deg = std::acos(-1.0) / 180.0;
    const double turns[] = {0.0, 5.0, 25.0, 60.0, 95.0};
    for (int i = 0; i < 5; ++i) {
        Move m;
        m.start = Vec3(-2.0, 3.0 + 3.5 * i, 8.0);
        m.end = Vec3(22.0, 4.0 + 3.5 * i, 7.0);
        m.axis = Vec3(0.0, 0.0, 1.0);
        if (turns[i] > 0.0) m.startAxis = Vec3(std::sin(turns[i] * deg), 0.0, std::cos(turns[i] * deg));
        m.rapid = i == 3;
        m.tool = 1 + i % 2;
        m.source = SourceRef{0, 10 + i};
        path.moves.push_back(m);
    }
    const std::map<int, ToolRegions> regions = toolRegions(path, tools);
    const MovePieces pieces(path, regions, kDefaultTurnTolerance);
    // The sweeps' moves and regions (B both, C the cutting part, S the shank), in order.
    std::vector<std::size_t> owners{0, 1};
    std::string kinds = "BB";
    for (const char region : {'C', 'S'})
        for (int k = 0; k < 3; ++k) owners.push_back(2), kinds += region;
    owners.push_back(3), kinds += 'B';
    for (const char region : {'C', 'S'})
        for (int k = 0; k < 10; ++k) owners.push_back(4), kinds += region;
    REQUIRE(pieces.size() == owners.size());
    for (std::size_t i = 0; i < owners.size(); ++i) {
        INFO("sweep " << i);
        CHECK(pieces.move(i) == owners[i]);
        CHECK("BCS"[int(pieces.regions(i))] == kinds[i]);
        // Each region's pieces start where the one before ends, and keep the move's tool and
        // source; the first starts and the last ends with the move.
        const Move piece = pieces.piece(i);
        const Move& whole = path.moves[owners[i]];
        CHECK(piece.tool == whole.tool);
        CHECK(piece.source.line == whole.source.line);
        const bool first = i == 0 || owners[i - 1] != owners[i] || kinds[i - 1] != kinds[i];
        const bool last = i + 1 == owners.size() || owners[i + 1] != owners[i] || kinds[i + 1] != kinds[i];
        if (first) CHECK(glm::length(piece.start - whole.start) < 1e-12);
        else CHECK(glm::length(piece.start - pieces.piece(i - 1).end) < 1e-12);
        if (last) CHECK(glm::length(piece.end - whole.end) < 1e-12);
        if (!first && piece.startAxis) CHECK(glm::length(*piece.startAxis - pieces.piece(i - 1).axis) < 1e-12);
    }
    // A turn within rounding of a multiple of the piece's takes that many pieces: 150 degrees,
    // whose quotient rounds up past 15, takes 15 (30 sweeps with the shank's).
    ToolPath even = path;
    even.moves.resize(1);
    even.moves[0].startAxis = Vec3(std::sin(150.0 * deg), 0.0, std::cos(150.0 * deg));
    REQUIRE(std::ceil(150.0 * deg / kMaxPieceTurn) == 16.0);
    CHECK(MovePieces(even, regions, kDefaultTurnTolerance).size() == 30);
    // Batches and threads change nothing; the statistics are per move, the progress in moves.
    TriDexelStock reference = TriDexelStock::fromBox(kStockBox, 0.3);
    std::vector<std::size_t> done;
    CutOptions one;
    one.threads = 1;
    one.progress = [&](std::size_t moves, std::size_t total) {
        CHECK(total == path.moves.size());
        done.push_back(moves);
    };
    const CutResult a = cutStock(reference, path, tools, one);
    REQUIRE(a.moves.size() == path.moves.size());
    REQUIRE(a.moves[4].removed > 50.0);
    // The turning pieces' node trees end most batches (the linear-node budget): the moves done
    // so far, in order, up to all of them.
    CHECK(std::is_sorted(done.begin(), done.end()));
    CHECK(done.back() == path.moves.size());
    for (const std::size_t batch : {1, 2, 7}) {
        std::vector<double> oneThread;  // the removed volumes on one thread, in this batch size
        for (const int threads : {1, 2}) {
            INFO(threads << " threads, batches of " << batch << " pieces");
            TriDexelStock stock = TriDexelStock::fromBox(kStockBox, 0.3);
            CutOptions opt;
            opt.threads = threads;
            opt.batchMoves = batch;
            done.clear();
            opt.progress = [&](std::size_t moves, std::size_t) { done.push_back(moves); };
            const CutResult b = cutStock(stock, path, tools, opt);
            CHECK(sameStock(reference, stock));
            for (std::size_t i = 0; i < path.moves.size(); ++i) {
                // A dexel of the last row or column inside the 0.3 mm lattice weighs its share of a
                // cell (Lattice::share), so a move's sum, grouped by batch, rounds by batch: the
                // same to the last bit for any thread count, and to 1e-12 for any batch size.
                if (threads == 1) oneThread.push_back(b.moves[i].removed);
                else CHECK(b.moves[i].removed == oneThread[i]);
                CHECK(b.moves[i].removed == Approx(a.moves[i].removed).epsilon(1e-12));
                CHECK(b.moves[i].changed == a.moves[i].changed);
            }
            CHECK(std::is_sorted(done.begin(), done.end()));
            CHECK(done.back() == path.moves.size());
            // Batches of one sweep: the moves before the sweep that comes next.
            if (batch == 1) {
                std::vector<std::size_t> expected;
                for (std::size_t i = 1; i <= owners.size(); ++i) expected.push_back(i == owners.size() ? 5 : owners[i]);
                CHECK(done == expected);
            }
        }
    }
}

TEST_CASE("cut: a rapid through material is a collision with its source line", "[stock][cut]") {
    TriDexelStock stock = TriDexelStock::fromBox(kStockBox, 0.25);
    ToolPath path;
    path.files.push_back("part.nc");
    Move safe;  // above the stock: no contact
    safe.start = Vec3(-5, 10, 12), safe.end = Vec3(25, 10, 12), safe.rapid = true, safe.tool = 1;
    safe.source = {0, 3};
    Move crash = safe;  // through the top 2 mm of the stock
    crash.start = Vec3(-5, 5, 8), crash.end = Vec3(25, 5, 8), crash.source = {0, 4};
    Move feed = crash;  // the same cut as a feed move: no collision
    feed.rapid = false, feed.start.y = feed.end.y = 15, feed.source = {0, 5};
    path.moves = {safe, crash, feed};
    const CutResult res = cutStock(stock, path, testTools());
    REQUIRE(res.collisions.size() == 1);
    CHECK(res.collisions[0].move == 1);
    CHECK(res.collisions[0].kind == CollisionKind::Rapid);
    CHECK(path.where(res.collisions[0].source).str() == "part.nc:4");
    // A slot 4 wide, 2 deep, 20 long: 160 mm^3 up to the lattice's O(h) resolution.
    CHECK(res.collisions[0].volume == Approx(160.0).epsilon(0.05));
    CHECK(res.moves[0].changed == 0);
    CHECK(res.moves[2].removed == Approx(160.0).epsilon(0.05));
}

TEST_CASE("cut: material met by the shank is reported, and removed unless asked not to", "[stock][cut]") {
    // Flat D4 with 3 mm of flute under a 27 mm shank, fed along x at a tip height of 4 from
    // outside the stock to x = 15: the flutes cut heights 4..7 and the shank meets 7..10, each
    // over the footprint 15 x 4 plus the half disk at the end, 60 + 2 pi mm^2. A plunge would not
    // do: the flutes clear the hole before the shank reaches it.
    ToolTable tools;
    tools.emplace(9, flatEndMill(4.0, {3.0, 30.0}));
    ToolPath path;
    path.files.push_back("deep.nc");
    Move feed;
    feed.start = Vec3(-5, 10, 4), feed.end = Vec3(15, 10, 4), feed.tool = 9, feed.source = {0, 7};
    path.moves = {feed};
    const double layer = (60.0 + 2.0 * M_PI) * 3.0;
    for (bool remove : {false, true}) {
        TriDexelStock stock = TriDexelStock::fromBox(kStockBox, 0.2);
        CutOptions opt;
        opt.removeShankMaterial = remove;
        const CutResult res = cutStock(stock, path, tools, opt);
        REQUIRE(res.collisions.size() == 1);
        CHECK(res.collisions[0].kind == CollisionKind::Shank);
        CHECK(res.collisions[0].move == 0);
        CHECK(res.collisions[0].source.line == 7);
        CHECK(res.collisions[0].volume == Approx(layer).epsilon(0.03));
        const double lost =
            kStockBox.volume() - (stock.volume(Axis::X) + stock.volume(Axis::Y) + stock.volume(Axis::Z)) / 3;
        CHECK(lost == Approx(remove ? 2 * layer : layer).epsilon(0.03));
        CHECK(res.removedVolume == Approx(lost).epsilon(1e-9));  // the mean over the families
    }
}

/// Flat D4 with 1 mm of flute and a 2 mm stick-out in a D8 holder (tool 3), fed along x at tip
/// height z from outside kStockBox to x = 15, on line 9 of held.nc.
struct HeldFeed {
    ToolTable tools;
    ToolPath path;
    explicit HeldFeed(double z) {
        tools.emplace(3, withHolder(flatEndMill(4.0, {1.0, 2.0}), 8.0, 10.0));
        path.files.push_back("held.nc");
        Move feed;
        feed.start = Vec3(-5, 10, z), feed.end = Vec3(15, 10, z), feed.tool = 3, feed.source = {0, 9};
        path.moves = {feed};
    }
};

TEST_CASE("cut: the holder's share of what the region above the flutes meets is its own collision", "[stock][cut]") {
    // HeldFeed at a tip height of 4: the flutes cut heights 4..5, the shank meets 5..6 over the
    // footprint 15 x 4 plus the half disk at the end (60 + 2 pi mm^2), and the holder 6..10 over
    // 15 x 8 plus its half disk (120 + 8 pi). The x and y dexels lie half a spacing off those
    // heights, so that no dexel runs along a face the shank and the holder share; the footprints'
    // edges leave the families within 0.1 % of these.
    const HeldFeed held(4.0);
    const double narrow = 60.0 + 2.0 * M_PI, wide = 120.0 + 8.0 * M_PI;
    const double flutes = narrow, shank = narrow, holder = 4.0 * wide;
    for (bool remove : {false, true}) {
        INFO("remove " << remove);
        TriDexelStock stock = TriDexelStock::fromBox(kStockBox, 0.2);
        CutOptions opt;
        opt.removeShankMaterial = remove;
        const CutResult res = cutStock(stock, held.path, held.tools, opt);
        REQUIRE(res.collisions.size() == 2);
        CHECK(res.collisions[0].kind == CollisionKind::Shank);
        CHECK(res.collisions[0].volume == Approx(shank).epsilon(0.005));
        CHECK(res.collisions[1].kind == CollisionKind::Holder);
        CHECK(res.collisions[1].source.line == 9);
        CHECK(res.collisions[1].volume == Approx(holder).epsilon(0.005));
        CHECK(res.holderVolume == Approx(holder).epsilon(0.005));
        CHECK(res.shankVolume == Approx(shank + holder).epsilon(0.005));
        const double lost =
            kStockBox.volume() - (stock.volume(Axis::X) + stock.volume(Axis::Y) + stock.volume(Axis::Z)) / 3;
        CHECK(lost == Approx(remove ? flutes + shank + holder : flutes).epsilon(0.005));
    }
}

TEST_CASE("cut: the region above the flutes measures what it meets once, whether or not it removes it", "[stock][cut]") {
    // HeldFeed with its tip at 4.1: the face the shank and the holder share lies on a row of x and
    // y dexels, which both parts' sweeps reach. Subtracted part by part, that row is removed once;
    // measured without subtracting it was counted twice (12 mm^3 more in y).
    const HeldFeed held(4.1);
    std::array<double, 2> shank{};
    for (bool remove : {false, true}) {
        TriDexelStock stock = TriDexelStock::fromBox(kStockBox, 0.2);
        CutOptions opt;
        opt.removeShankMaterial = remove;
        shank[remove] = cutStock(stock, held.path, held.tools, opt).shankVolume;
    }
    CHECK(shank[0] == Approx(shank[1]).epsilon(1e-9));
}

TEST_CASE("cut: material met by a holder is a collision of the holder", "[stock][cut]") {
    // Flat D10, 15 mm of flute, 20 mm stick-out, in a D30 holder, plunged from above to 22 mm
    // below the stock's top face: the flutes and the shank go down a hole of radius 5 that the
    // flutes cut, and the holder's last 2 mm meet the ring between radii 5 and 15, 400 pi mm^3.
    const Box box{Vec3(-20, -20, -30), Vec3(20, 20, 0)};
    ToolTable tools;
    tools.emplace(1, withHolder(flatEndMill(10.0, {15.0, 20.0}), 30.0, 20.0));
    tools.emplace(2, flatEndMill(10.0, {15.0, 20.0}));
    for (int tool : {1, 2}) {
        ToolPath path;
        path.files.push_back("plunge.nc");
        Move down;
        down.start = Vec3(0.5, 0.25, 5), down.end = Vec3(0.5, 0.25, -22), down.tool = tool, down.source = {0, 3};
        path.moves = {down};
        TriDexelStock stock = TriDexelStock::fromBox(box, 0.25);
        const CutResult res = cutStock(stock, path, tools);
        const double hole = M_PI * 25.0 * 22.0, ring = M_PI * (225.0 - 25.0) * 2.0;
        INFO("tool " << tool);
        if (tool == 2) {
            CHECK(res.collisions.empty());
            CHECK(res.removedVolume == Approx(hole).epsilon(0.01));
            continue;
        }
        // The shank goes down the flutes' hole and meets nothing.
        REQUIRE(res.collisions.size() == 1);
        CHECK(res.collisions[0].kind == CollisionKind::Holder);
        CHECK(res.collisions[0].volume == Approx(ring).epsilon(0.01));
        CHECK(res.removedVolume == Approx(hole + ring).epsilon(0.01));
    }
}

TEST_CASE("cut: a move whose tool is not in the table throws", "[stock][cut]") {
    TriDexelStock stock = TriDexelStock::fromBox(kStockBox, 1.0);
    ToolPath path;
    path.files.push_back("x.nc");
    Move m;
    m.tool = 42, m.source = {0, 12};
    path.moves = {m};
    CHECK_THROWS_AS(cutStock(stock, path, testTools()), Error);
    try {
        cutStock(stock, path, testTools());
    } catch (const Error& e) {
        CHECK(std::string(e.what()).find("x.nc:12") != std::string::npos);
    }
}

TEST_CASE("cut: progress is reported per batch, the same for any thread count", "[stock][cut]") {
    const ToolPath path = randomProgram(5, 130);
    std::vector<std::size_t> seen[2];
    for (int run = 0; run < 2; ++run) {
        TriDexelStock stock = TriDexelStock::fromBox(kStockBox, 0.5);
        CutOptions opt;
        opt.threads = run ? 2 : 1;
        opt.batchMoves = 32;
        opt.progress = [&](std::size_t done, std::size_t total) {
            CHECK(total == 130);
            seen[run].push_back(done);
        };
        cutStock(stock, path, testTools(), opt);
    }
    CHECK(seen[0] == std::vector<std::size_t>{32, 64, 96, 128, 130});
    CHECK(seen[0] == seen[1]);
}

TEST_CASE("cut: culling visits few dexels that do not change", "[stock][cut]") {
    // One long slot through a fresh stock: every visited z dexel in the slot changes; the box
    // adds the rounded ends and the dexels just outside the slot's width.
    TriDexelStock stock = TriDexelStock::fromBox(kStockBox, 0.2, FamilySet::only(Axis::Z));
    ToolPath path;
    path.files.push_back("slot.nc");
    Move m;
    m.start = Vec3(2, 10, 8), m.end = Vec3(18, 10, 8), m.tool = 1;
    path.moves = {m};
    const CutResult res = cutStock(stock, path, testTools());
    REQUIRE(res.moves[0].changed > 0);
    CHECK(double(res.moves[0].visited) / double(res.moves[0].changed) < 1.2);
    CHECK(res.moves[0].bounded >= res.moves[0].visited);
    CHECK(double(res.moves[0].bounded) / double(res.moves[0].changed) < 1.5);
    // Slot 16 x 4 plus two half disks of radius 2, 2 deep.
    CHECK(res.moves[0].removed == Approx((16.0 * 4.0 + M_PI * 4.0) * 2.0).epsilon(0.03));
}

TEST_CASE("cut: a floor and a wall exactly on lattice lines: the three families agree", "[stock][cut]") {
    // h = 0.5 from the origin puts lattice lines at 0.25 + 0.5 k: a flat D4 pass along y with its
    // tip at z = 7.75 and its centre at x = 8.25 leaves a floor on the z = 7.75 lattice plane and a
    // wall on the x = 10.25 one. Lines lying in the floor or the wall are in the (closed) tool, so
    // the points on them are cut, and the dexels across them must agree.
    const double h = 0.5;
    TriDexelStock stock = TriDexelStock::fromBox(kStockBox, h);
    const Lattice& l = stock.lattice();
    const int kFloor = 15, iWall = 20;
    REQUIRE(l.coord(Axis::Z, kFloor) == 7.75);
    REQUIRE(l.coord(Axis::X, iWall) == 10.25);
    ToolPath path;
    path.files.push_back("pocket.nc");
    Move m;
    m.start = Vec3(8.25, -5, 7.75), m.end = Vec3(8.25, 25, 7.75), m.tool = 1, m.source = {0, 1};
    path.moves = {m};
    const CutResult res = cutStock(stock, path, testTools());
    REQUIRE(res.removedVolume > 0.0);
    std::size_t mismatches = 0;
    for (int k = 0; k < l.n[2]; ++k)
        for (int j = 0; j < l.n[1]; ++j)
            for (int i = 0; i < l.n[0]; ++i) {
                const bool x = stock.inside(Axis::X, i, j, k), y = stock.inside(Axis::Y, i, j, k),
                           z = stock.inside(Axis::Z, i, j, k);
                mismatches += (x != y) || (y != z);
            }
    CHECK(mismatches == 0);
    // On the floor plane under the slot and on the wall plane beside it, nothing is left.
    CHECK_FALSE(stock.inside(Axis::Z, 16, 20, kFloor));
    CHECK_FALSE(stock.inside(Axis::X, iWall, 20, 18));
    // Just below the floor and just past the wall, material.
    CHECK(stock.inside(Axis::Z, 16, 20, kFloor - 1));
    CHECK(stock.inside(Axis::X, iWall + 1, 20, 18));
}


TEST_CASE("cut: a move far past the stock cuts what the move clipped to the stock cuts", "[stock][cut]") {
    // Issue 15: G1 X2e8 crashed the cutting loop (an index past int at small spacings). The stock is 20 x 20 x 10;
    // the near moves already start and end with the tool (radius 2) clear of it, and the far
    // moves run along the same lines.
    const double h = 0.25;
    struct Case {
        const char* what;
        Vec3 nearStart, nearEnd, farStart, farEnd;
    };
    const Case cases[] = {
        {"along +x", Vec3(5, 7.3, 6), Vec3(40, 7.3, 6), Vec3(5, 7.3, 6), Vec3(2e9, 7.3, 6)},
        {"along -y", Vec3(12.1, 15, 7.5), Vec3(12.1, -20, 7.5), Vec3(12.1, 15, 7.5), Vec3(12.1, -2e9, 7.5)},
        {"oblique, both ends far", Vec3(-30, -25, 6.5), Vec3(30, 35, 6.5), Vec3(-30 - 1e9, -25 - 1e9, 6.5),
         Vec3(30 + 1e9, 35 + 1e9, 6.5)},
        {"down through the floor", Vec3(9, 9, 20), Vec3(9, 9, -20), Vec3(9, 9, 20), Vec3(9, 9, -1e9)},
    };
    for (const Case& c : cases) {
        INFO(c.what);
        auto run = [&](const Vec3& start, const Vec3& end) {
            TriDexelStock stock = TriDexelStock::fromBox(kStockBox, h);
            const CutResult r = cutStock(stock, testing::slotPath(start, end, "far.nc"), testTools());
            return std::make_pair(std::move(stock), r.removedVolume);
        };
        const auto [nearStock, nearVolume] = run(c.nearStart, c.nearEnd);
        const auto [farStock, farVolume] = run(c.farStart, c.farEnd);
        REQUIRE(nearVolume > 10.0);
        // Ends within kEnd of each other move the volume by at most kEnd times the faces the cut
        // makes (under 1,000 mm^2 here), about 3e-5 of it.
        const double kEnd = 1e-5;
        CHECK(std::abs(farVolume - nearVolume) <= kEnd * 1000.0);
        // Every dexel has the same segments, to the sweep's stated accuracy (coordinates of 1e9
        // mm carry 1e-7 mm of rounding into the sweep's frame).
        double worst = 0.0;
        std::size_t differentCounts = 0;
        for (int ax = 0; ax < 3; ++ax) {
            const DexelFamily& fa = nearStock.family(axisFromIndex(ax));
            const DexelFamily& fb = farStock.family(axisFromIndex(ax));
            for (int ic = 0; ic < fa.nc(); ++ic)
                for (int ib = 0; ib < fa.nb(); ++ib) {
                    const SegmentSpan sa = fa.segments(ib, ic), sb = fb.segments(ib, ic);
                    if (sa.size != sb.size) {
                        ++differentCounts;
                        continue;
                    }
                    for (std::size_t k = 0; k < sa.size; ++k)
                        worst = std::max({worst, std::abs(double(sa[k].lo) - double(sb[k].lo)),
                                          std::abs(double(sa[k].hi) - double(sb[k].hi))});
                }
        }
        CHECK(differentCounts == 0);
        CHECK(worst <= kEnd);
    }
    SECTION("a move wholly far away, as after G1 X2e9, removes nothing") {
        for (const Vec3& far : {Vec3(2e9, 5, 5), Vec3(-2e9, 5, 5), Vec3(5, 3e9, 5), Vec3(5, 5, -3e9)}) {
            ToolPath path;
            path.files.push_back("far.nc");
            Move m;
            m.start = far;
            m.end = far + Vec3(0, 0, 1);
            m.tool = 1;
            m.source = SourceRef{0, 1};
            path.moves.push_back(m);
            TriDexelStock stock = TriDexelStock::fromBox(kStockBox, h);
            CHECK(cutStock(stock, path, testTools()).removedVolume == 0.0);
        }
    }
}
