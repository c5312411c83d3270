// The graph journal: bytes written per keyframe stay flat over a long drive, a torn last record
// (a crash mid-append) is dropped at every byte it can be cut at, a corrupt record is an error,
// and a compaction changes nothing that loads.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "state_fixture.hpp"

namespace {

namespace fs = std::filesystem;
using namespace liod;
using liod::test::fresh_state_dir;
using liod::test::read_bytes;
using liod::test::StateFixture;
using liod::test::write_bytes;

// Bytes this process handed to write(2) so far (/proc/self/io wchar): what the writer writes,
// measured from outside it.
std::uint64_t bytes_written() {
  std::ifstream io("/proc/self/io");
  std::string key;
  std::uint64_t value = 0;
  while (io >> key >> value) {
    if (key == "wchar:") return value;
  }
  return 0;
}

void expect_same_graph(const PersistedGraph& a, const PersistedGraph& b) {
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  ASSERT_EQ(a.factors.size(), b.factors.size());
  for (std::size_t i = 0; i < a.nodes.size(); ++i) {
    EXPECT_EQ(a.nodes[i].id, b.nodes[i].id);
    EXPECT_EQ(a.nodes[i].run, b.nodes[i].run);
    EXPECT_EQ(a.nodes[i].pose.matrix(), b.nodes[i].pose.matrix()) << "node " << i;
  }
  for (std::size_t i = 0; i < a.factors.size(); ++i) {
    EXPECT_EQ(a.factors[i].from_id, b.factors[i].from_id);
    EXPECT_EQ(a.factors[i].to_id, b.factors[i].to_id);
    EXPECT_EQ(a.factors[i].loop, b.factors[i].loop);
    EXPECT_EQ(a.factors[i].measured.matrix(), b.factors[i].measured.matrix());
    EXPECT_EQ(a.factors[i].information, b.factors[i].information);
  }
}

// 2000 keyframes, a solve moving the newest 200 poses every 50 (so that the journal's pose
// updates outgrow the snapshot and it is compacted): the bytes written per keyframe (keyframe
// files, journal, snapshots) over all 2000 stay within 1.5 times those over the first 500 (a
// compaction writes the snapshot once per journal of twice its size, so its cost per keyframe
// is bounded, wherever one falls), no 500 average more than 4 kB a keyframe, and a keyframe never
// waits for more than one sync. Rewriting the whole graph per keyframe wrote 4 times more per
// keyframe over the 2000 than over the first 500 (425 kB against 106 kB), 744 kB in the last 500.
TEST(StateJournal, BytesWrittenPerKeyframeStayFlat) {
  const fs::path dir = fresh_state_dir("flat");
  constexpr std::size_t kKeyframes = 2000;
  constexpr std::size_t kBlock = 500;
  StateFixture f;
  f.points = 10;
  StateWriter writer(dir, StateWriterOptions{1.5, 64 * 1024});
  std::vector<double> per_keyframe;  // bytes per keyframe in each block
  std::uint64_t block_start = bytes_written();
  for (std::size_t n = 1; n <= kKeyframes; ++n) {
    test::grow(f, n);
    if (n % 50 == 0) test::bend(f, 200, 0.01);
    writer.save(f.keyframes, f.graph);
    if (n % kBlock == 0) {
      const std::uint64_t now = bytes_written();
      per_keyframe.push_back(static_cast<double>(now - block_start) / kBlock);
      block_start = now;
    }
  }
  for (std::size_t b = 0; b < per_keyframe.size(); ++b) {
    std::cout << "keyframes " << b * kBlock << "-" << (b + 1) * kBlock << ": " << per_keyframe[b] << " bytes per keyframe\n";
  }
  ASSERT_EQ(per_keyframe.size(), 4U);
  EXPECT_GT(per_keyframe.front(), 0.0);
  double all = 0.0;
  for (const double b : per_keyframe) {
    EXPECT_LT(b, 4000.0);
    all += b / static_cast<double>(per_keyframe.size());
  }
  std::cout << "all " << kKeyframes << " keyframes: " << all << " bytes per keyframe\n";
  EXPECT_LT(all, 1.5 * per_keyframe.front());
  EXPECT_GE(writer.stats().compactions, 2U);
  EXPECT_LE(writer.stats().syncs, kKeyframes);
  writer.flush();
  const PersistedState s = load_state(dir);
  ASSERT_EQ(s.keyframes.size(), kKeyframes);
  for (std::size_t i = 0; i < kKeyframes; ++i) ASSERT_TRUE(s.poses[i].isApprox(f.graph.pose(i))) << i;
  fs::remove_all(dir);
}

// The journal of 8 keyframes, cut at every byte of its last record (the 8th keyframe's last
// factor): it loads with the records before it, names the torn record, and a new run appends
// after the cut.
TEST(StateJournal, TornLastRecordIsDroppedAtEveryCut) {
  const fs::path dir = fresh_state_dir("torn");
  StateFixture f;
  f.points = 5;
  std::uint64_t before_last_save = 0;
  std::uint64_t after_last_save = 0;
  {
    StateWriter writer(dir);
    test::grow(f, 7);
    writer.save(f.keyframes, f.graph);
    before_last_save = writer.stats().journal_bytes;
    test::grow(f, 8);
    writer.save(f.keyframes, f.graph);
    after_last_save = writer.stats().journal_bytes;
  }
  const std::string journal = read_bytes(dir / "journal.bin");
  ASSERT_EQ(journal.size(), after_last_save);
  const std::size_t factor_record = after_last_save - before_last_save - (9 + 8 + 4 + 56);  // the node record before it
  const std::size_t last_start = journal.size() - factor_record;
  const PersistedGraph whole = load_graph(dir);
  ASSERT_EQ(whole.nodes.size(), 8U);
  ASSERT_EQ(whole.factors.size(), 7U);
  for (std::size_t cut = last_start; cut < journal.size(); ++cut) {
    write_bytes(dir / "journal.bin", journal.substr(0, cut));
    PersistedGraph g;
    ASSERT_NO_THROW(g = load_graph(dir)) << "cut at " << cut;
    EXPECT_EQ(g.nodes.size(), 8U) << "cut at " << cut;
    EXPECT_EQ(g.factors.size(), 6U) << "cut at " << cut;
    EXPECT_EQ(g.notes.size(), cut == last_start ? 0U : 1U) << "cut at " << cut;
    if (cut > last_start) {
      EXPECT_NE(g.notes.front().find("torn"), std::string::npos) << g.notes.front();
    }
  }
  // What a power loss leaves: the file extended, its last bytes zeros.
  write_bytes(dir / "journal.bin", journal.substr(0, last_start) + std::string(2 * factor_record, '\0'));
  EXPECT_EQ(load_graph(dir).factors.size(), 6U);
  // A new run cuts the torn record off and appends after it.
  write_bytes(dir / "journal.bin", journal.substr(0, last_start + 17));
  {
    StateWriter writer(dir);
    ASSERT_EQ(writer.graph().notes.size(), 1U);
    StateFixture next;
    next.first_id = writer.first_keyframe_id();
    next.points = 5;
    test::grow(next, 3);
    writer.save(next.keyframes, next.graph);
  }
  const PersistedState s = load_state(dir);
  EXPECT_EQ(s.keyframes.size(), 11U);
  EXPECT_EQ(s.factors.size(), 6U + 2U);
  EXPECT_TRUE(s.notes.empty());
  fs::remove_all(dir);
}

TEST(StateJournal, CorruptRecordIsDetectedByItsChecksum) {
  const fs::path dir = fresh_state_dir("crc");
  StateFixture f;
  f.points = 5;
  test::grow(f, 6);
  {
    StateWriter writer(dir);
    writer.save(f.keyframes, f.graph);
  }
  const std::string journal = read_bytes(dir / "journal.bin");
  // A flipped bit in the first record's pose (the header is 28 bytes, the framing 5).
  std::string flipped = journal;
  flipped[28 + 5 + 20] = static_cast<char>(flipped[28 + 5 + 20] ^ 0x01);
  write_bytes(dir / "journal.bin", flipped);
  try {
    load_graph(dir);
    ADD_FAILURE() << "a corrupt record loaded";
  } catch (const StateError& e) {
    EXPECT_NE(std::string(e.what()).find("journal.bin record 0 at byte 28: checksum mismatch"), std::string::npos) << e.what();
  }
  // The same flip in the last record: indistinguishable from a torn append, dropped and named.
  flipped = journal;
  flipped[journal.size() - 30] = static_cast<char>(flipped[journal.size() - 30] ^ 0x01);
  write_bytes(dir / "journal.bin", flipped);
  const PersistedGraph g = load_graph(dir);
  EXPECT_EQ(g.factors.size(), 4U);
  ASSERT_EQ(g.notes.size(), 1U);
  fs::remove_all(dir);
}

// A compaction (snapshot + fresh journal) loads as the journal did, in each of its steps: the new
// snapshot beside the old journal it replaces, and after the swap.
TEST(StateJournal, LoadAfterCompactionEqualsLoadBefore) {
  const fs::path dir = fresh_state_dir("compaction");
  StateFixture f;
  f.points = 5;
  StateWriter writer(dir, StateWriterOptions{1e9, 1ULL << 40});  // compacts only when told
  for (std::size_t n = 1; n <= 60; ++n) {
    test::grow(f, n);
    if (n % 10 == 0) test::bend(f, 8, 0.02);
    writer.save(f.keyframes, f.graph);
  }
  writer.flush();
  EXPECT_FALSE(fs::exists(dir / "graph.bin"));
  const PersistedGraph before = load_graph(dir);
  ASSERT_EQ(before.nodes.size(), 60U);
  const std::uint64_t journal_before = fs::file_size(dir / "journal.bin");
  writer.compact();
  EXPECT_EQ(writer.stats().compactions, 1U);
  EXPECT_LT(fs::file_size(dir / "journal.bin"), 64U);
  EXPECT_LT(fs::file_size(dir / "graph.bin"), journal_before);
  expect_same_graph(before, load_graph(dir));
  // A compaction that has put its snapshot in place but not yet its fresh journal (as a save
  // leaves it until the next one): the old journal is recognised as folded in.
  StateWriter eager(fresh_state_dir("compaction-eager"), StateWriterOptions{0.0, 0});
  StateFixture e;
  e.points = 5;
  test::grow(e, 5);
  eager.save(e.keyframes, e.graph);
  ASSERT_EQ(eager.stats().compactions, 1U);
  const PersistedGraph midway = load_graph(eager.directory());
  EXPECT_EQ(midway.nodes.size(), 5U);
  test::grow(e, 6);
  eager.save(e.keyframes, e.graph);
  eager.flush();
  EXPECT_EQ(load_graph(eager.directory()).nodes.size(), 6U);
  // Keep writing after the compaction: the journal continues from the snapshot.
  test::grow(f, 70);
  writer.save(f.keyframes, f.graph);
  writer.flush();
  EXPECT_EQ(load_state(dir).keyframes.size(), 70U);
  fs::remove_all(dir);
  fs::remove_all(eager.directory());
}

}  // namespace
