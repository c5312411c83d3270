#include "liod/daemon/backend_worker.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <sstream>

#include "liod/backend/map_store.hpp"

#include "liod/daemon/percentile.hpp"

namespace liod {

BackendWorker::BackendWorker(const Config& config) : config_(config), backend_(config) {
  if (config.backend.persist) writer_ = std::make_unique<StateWriter>(config.output.state_dir);
}

BackendWorker::~BackendWorker() = default;

bool BackendWorker::process(const Keyframe& keyframe) {
  const std::size_t checks_before = backend_.loop_checks().size();
  const bool closed = backend_.add_keyframe(keyframe);
  const auto& checks = backend_.loop_checks();
  for (std::size_t i = checks_before; i < checks.size(); ++i) {
    const LoopCheck& c = checks[i];
    const auto& kf = backend_.keyframes();
    spdlog::debug("loop candidate {} -> {}: {} (similarity {:.2f} m = max({:.2f}, {:.2f}), rms {:.3f} m, inliers {:.2f}, dz {:.2f} m, tilt "
                  "{:.2f} deg, {:.0f} ms)",
                  kf[c.current].id, kf[c.candidate].id, to_string(c.outcome), c.similarity_m, c.similarity_forward_m,
                  c.similarity_backward_m, c.rms_m,
                  c.inlier_fraction, c.dz_m, c.tilt_deg, c.check_ms);
  }
  if (closed) {
    const LoopCheck& c = checks.back();
    const auto& kf = backend_.keyframes();
    spdlog::info("loop closed: keyframe {} -> {} ({:.1f} s earlier), correction now {:.2f} m, solve {:.1f} ms",
                 kf[c.current].id, kf[c.candidate].id, kf[c.current].time - kf[c.candidate].time,
                 backend_.correction().translation().norm(), backend_.stats().solve_ms.back());
    const Eigen::Isometry3d correction = backend_.correction();
    std::lock_guard lock(correction_mutex_);
    correction_ = correction;
  }
  if (writer_) {
    try {
      writer_->save(backend_.keyframes(), backend_.graph());
    } catch (const StateError& e) {
      spdlog::warn("backend state not saved: {}", e.what());
    }
  }
  return closed;
}

void BackendWorker::finish() {
  if (!writer_) return;
  try {
    writer_->save(backend_.keyframes(), backend_.graph());
    write_map_pcd(writer_->directory() / "map.pcd", backend_.global_map(config_.backend.map_voxel_m));
  } catch (const StateError& e) {
    spdlog::warn("backend state not saved: {}", e.what());
  }
}

Eigen::Isometry3d BackendWorker::correction() const {
  std::lock_guard lock(correction_mutex_);
  return correction_;
}

std::string BackendWorker::summary() const {
  const auto& s = backend_.stats();
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(1);
  out << "backend: " << s.keyframes << " keyframes, " << s.loops_accepted << " loop closures, " << s.loops_rejected
      << " candidates rejected (";
  for (std::size_t i = 1; i < s.outcomes.size(); ++i) {
    if (i == static_cast<std::size_t>(LoopOutcome::kNoCandidate)) continue;
    out << (i > 2 ? ", " : "") << to_string(static_cast<LoopOutcome>(i)) << ' ' << s.outcomes[i];
  }
  out << ")\n";
  out << "backend: loop checks median " << percentile(s.check_ms, 0.5) << " ms, max " << percentile(s.check_ms, 1.0)
      << " ms; pose-graph solves " << s.solve_ms.size() << ", median " << percentile(s.solve_ms, 0.5) << " ms, max "
      << percentile(s.solve_ms, 1.0) << " ms\n";
  return out.str();
}

}  // namespace liod
