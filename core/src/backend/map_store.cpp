#include "liod/backend/map_store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>

namespace liod {
namespace fs = std::filesystem;
namespace {

constexpr char kGraphMagic[8] = {'L', 'I', 'O', 'D', 'G', 'R', 'F', '1'};
constexpr char kKeyframeMagic[8] = {'L', 'I', 'O', 'D', 'K', 'F', 'R', '1'};
constexpr std::uint32_t kVersion = 1;
// Guards against a corrupt count asking for an absurd allocation.
constexpr std::uint64_t kMaxCount = 1ULL << 28;

// FNV-1a, 64 bit: enough to detect a torn or bit-flipped file (not an adversary).
std::uint64_t fnv1a(std::string_view bytes) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  return h;
}

std::string errno_text() { return std::strerror(errno); }

class Writer {
 public:
  template <typename T>
  void put(const T& v) {
    buffer_.append(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  void raw(const void* data, std::size_t n) { buffer_.append(static_cast<const char*>(data), n); }
  void pose(const Eigen::Isometry3d& t) {
    const Eigen::Quaterniond q(t.linear());
    for (int i = 0; i < 3; ++i) put(t.translation()(i));
    for (int i = 0; i < 4; ++i) put(q.coeffs()(i));  // x y z w
  }
  void points(const std::vector<Eigen::Vector3f>& p) {
    put(static_cast<std::uint64_t>(p.size()));
    for (const auto& v : p) raw(v.data(), 3 * sizeof(float));
  }
  std::string finish() {
    put(fnv1a(buffer_));
    return std::move(buffer_);
  }

 private:
  std::string buffer_;
};

class Reader {
 public:
  Reader(std::string bytes, fs::path path) : bytes_(std::move(bytes)), path_(std::move(path)) {}
  [[noreturn]] void fail(const std::string& what) const { throw StateError(path_.string() + ": " + what); }
  void check(const char (&magic)[8]) {
    if (bytes_.size() < 8 + 8 + 8 || std::memcmp(bytes_.data(), magic, 8) != 0) {
      fail("not a liod state file (bad magic or truncated)");
    }
    const std::string_view body(bytes_.data(), bytes_.size() - 8);
    std::uint64_t stored = 0;
    std::memcpy(&stored, bytes_.data() + bytes_.size() - 8, 8);
    if (stored != fnv1a(body)) fail("checksum mismatch: the file is corrupt or was partially written");
    end_ = bytes_.size() - 8;
    offset_ = 8;
    if (get<std::uint32_t>() != kVersion) fail("unsupported version");
    (void)get<std::uint32_t>();
  }
  template <typename T>
  T get() {
    T v{};
    take(&v, sizeof(T));
    return v;
  }
  std::uint64_t count() {
    const auto n = get<std::uint64_t>();
    if (n > kMaxCount) fail("implausible element count " + std::to_string(n));
    return n;
  }
  Eigen::Isometry3d pose() {
    Eigen::Vector3d t;
    Eigen::Quaterniond q;
    for (int i = 0; i < 3; ++i) t(i) = get<double>();
    for (int i = 0; i < 4; ++i) q.coeffs()(i) = get<double>();
    if (!t.allFinite() || !q.coeffs().allFinite() || std::abs(q.norm() - 1.0) > 1e-6) fail("invalid pose");
    Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
    out.linear() = q.normalized().toRotationMatrix();
    out.translation() = t;
    return out;
  }
  std::vector<Eigen::Vector3f> points() {
    const auto n = count();
    if (n * 3 * sizeof(float) > end_ - offset_) fail("truncated point list");
    std::vector<Eigen::Vector3f> out(n);
    for (auto& p : out) take(p.data(), 3 * sizeof(float));
    return out;
  }
  void done() const {
    if (offset_ != end_) fail("trailing bytes after the content");
  }

 private:
  void take(void* out, std::size_t n) {
    if (n > end_ - offset_) fail("truncated");
    std::memcpy(out, bytes_.data() + offset_, n);
    offset_ += n;
  }
  std::string bytes_;
  fs::path path_;
  std::size_t offset_ = 0;
  std::size_t end_ = 0;
};

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw StateError(path.string() + ": cannot open (" + errno_text() + ")");
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

fs::path keyframe_path(const fs::path& dir, std::uint64_t id) {
  return dir / "keyframes" / (std::to_string(id) + ".kf");
}

void fsync_directory(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw StateError(dir.string() + ": cannot open directory for fsync (" + errno_text() + ")");
  const int rc = ::fsync(fd);
  ::close(fd);
  if (rc != 0) throw StateError(dir.string() + ": fsync of the directory failed (" + errno_text() + ")");
}

void write_file(const fs::path& path, std::string_view bytes, bool durable) {
  const fs::path temp = path.string() + ".tmp";
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw StateError(temp.string() + ": cannot create (" + errno_text() + ")");
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = errno_text();
      ::close(fd);
      throw StateError(temp.string() + ": write failed (" + why + ")");
    }
    done += static_cast<std::size_t>(n);
  }
  // Data on disk before the rename makes it visible; the directory fsync makes the rename durable.
  if (durable && ::fsync(fd) != 0) {
    const std::string why = errno_text();
    ::close(fd);
    throw StateError(temp.string() + ": fsync failed (" + why + ")");
  }
  ::close(fd);
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    throw StateError(path.string() + ": rename from the temp file failed (" + errno_text() + ")");
  }
  if (durable) fsync_directory(path.has_parent_path() ? path.parent_path() : fs::path("."));
}

}  // namespace

void write_file_atomically(const fs::path& path, std::string_view bytes) { write_file(path, bytes, true); }

void write_map_pcd(const fs::path& path, const std::vector<Eigen::Vector3d>& points) {
  std::ostringstream header;
  header << "# .PCD v0.7 - liod global map\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH "
         << points.size() << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << points.size() << "\nDATA binary\n";
  std::string bytes = header.str();
  bytes.reserve(bytes.size() + points.size() * 12);
  for (const auto& p : points) {
    const float v[3] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())};
    bytes.append(reinterpret_cast<const char*>(v), sizeof v);
  }
  write_file_atomically(path, bytes);
}

StateWriter::StateWriter(fs::path directory) : directory_(std::move(directory)) {
  std::error_code ec;
  fs::create_directories(directory_ / "keyframes", ec);
  if (ec) throw StateError(directory_.string() + ": cannot create the state directory (" + ec.message() + ")");
  // Temp files are what a crash mid-write leaves behind; the committed files never depend on them.
  for (const auto& dir : {directory_, directory_ / "keyframes"}) {
    for (const auto& entry : fs::directory_iterator(dir)) {
      if (entry.path().extension() == ".tmp") fs::remove(entry.path(), ec);
    }
  }
}

void write_keyframe_file(const fs::path& directory, const BackendKeyframe& k, bool durable) {
  Writer w;
  w.raw(kKeyframeMagic, 8);
  w.put(kVersion);
  w.put(std::uint32_t{0});
  w.put(k.id);
  w.put(k.time);
  w.pose(k.odometry_pose);
  w.points(k.planes);
  w.points(k.edges);
  w.points(k.similarity);
  write_file(keyframe_path(directory, k.id), w.finish(), durable);
}

BackendKeyframe read_keyframe_file(const fs::path& directory, std::uint64_t id) {
  const fs::path path = keyframe_path(directory, id);
  if (!fs::exists(path)) throw StateError(path.string() + ": missing");
  Reader k(read_all(path), path);
  k.check(kKeyframeMagic);
  BackendKeyframe kf;
  kf.id = k.get<std::uint64_t>();
  if (kf.id != id) k.fail("holds keyframe " + std::to_string(kf.id) + ", expected " + std::to_string(id));
  kf.time = k.get<double>();
  kf.odometry_pose = k.pose();
  kf.planes = k.points();
  kf.edges = k.points();
  kf.similarity = k.points();
  k.done();
  return kf;
}

KeyframeDirectory::KeyframeDirectory(fs::path directory, Kind kind) : directory_(std::move(directory)), kind_(kind) {
  std::error_code ec;
  fs::create_directories(directory_ / "keyframes", ec);
  if (ec) throw StateError(directory_.string() + ": cannot create the keyframe directory (" + ec.message() + ")");
}

KeyframeDirectory::~KeyframeDirectory() {
  if (kind_ != Kind::kScratch) return;
  std::error_code ec;  // best effort: a scratch directory left behind is only wasted space
  fs::remove_all(directory_, ec);
}

void KeyframeDirectory::write(const BackendKeyframe& keyframe) {
  // Scratch files need no fsync: they only have to survive until this process reads them back.
  write_keyframe_file(directory_, keyframe, kind_ == Kind::kState);
}

BackendKeyframe KeyframeDirectory::read(std::uint64_t id) const { return read_keyframe_file(directory_, id); }

void StateWriter::save(const std::vector<BackendKeyframe>& keyframes, const PoseGraph& graph) {
  for (; keyframes_written_ < keyframes.size(); ++keyframes_written_) {
    write_keyframe_file(directory_, keyframes[keyframes_written_], true);
  }
  std::vector<std::uint64_t> ids;
  ids.reserve(keyframes.size());
  for (const auto& k : keyframes) ids.push_back(k.id);
  save_graph(ids, graph);
}

void StateWriter::save_graph(const std::vector<std::uint64_t>& ids, const PoseGraph& graph) {
  Writer w;
  w.raw(kGraphMagic, 8);
  w.put(kVersion);
  w.put(std::uint32_t{0});
  w.put(static_cast<std::uint64_t>(ids.size()));
  for (std::size_t i = 0; i < ids.size(); ++i) {
    w.put(ids[i]);
    w.pose(graph.pose(i));
  }
  w.put(static_cast<std::uint64_t>(graph.factors().size()));
  for (const auto& f : graph.factors()) {
    w.put(static_cast<std::uint64_t>(f.from));
    w.put(static_cast<std::uint64_t>(f.to));
    w.put(static_cast<std::uint8_t>(f.loop ? 1 : 0));
    w.pose(f.measured);
    w.raw(f.information.data(), sizeof(double) * 36);
  }
  write_file_atomically(directory_ / "graph.bin", w.finish());
}

PersistedState load_state(const fs::path& directory) {
  const fs::path graph_path = directory / "graph.bin";
  if (!fs::exists(graph_path)) throw StateError(graph_path.string() + ": missing (no state was saved here)");
  Reader r(read_all(graph_path), graph_path);
  r.check(kGraphMagic);
  PersistedState state;
  const auto nodes = r.count();
  std::vector<std::uint64_t> ids(nodes);
  for (std::uint64_t i = 0; i < nodes; ++i) {
    ids[i] = r.get<std::uint64_t>();
    state.poses.push_back(r.pose());
  }
  const auto factors = r.count();
  for (std::uint64_t i = 0; i < factors; ++i) {
    PoseGraphFactor f;
    f.from = r.get<std::uint64_t>();
    f.to = r.get<std::uint64_t>();
    f.loop = r.get<std::uint8_t>() != 0;
    f.measured = r.pose();
    for (int k = 0; k < 36; ++k) f.information.data()[k] = r.get<double>();
    if (f.from >= nodes || f.to >= nodes) r.fail("factor " + std::to_string(i) + " names a node that does not exist");
    if (!f.information.allFinite()) r.fail("factor " + std::to_string(i) + " has a non-finite information matrix");
    state.factors.push_back(f);
  }
  r.done();
  for (std::uint64_t i = 0; i < nodes; ++i) {
    const fs::path path = keyframe_path(directory, ids[i]);
    if (!fs::exists(path)) throw StateError(path.string() + ": missing, but listed in " + graph_path.string());
    state.keyframes.push_back(read_keyframe_file(directory, ids[i]));
  }
  return state;
}

}  // namespace liod
