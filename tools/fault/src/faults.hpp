#pragma once
// One function per fault kind (apply_fault.cpp dispatches); each returns what it changed.

#include <string>

#include "liod/fault/fault_spec.hpp"
#include "liod/fault/recording.hpp"
#include "rng.hpp"

namespace liod::fault {

// packet_faults.cpp: which datagrams arrive, and in which order.
std::string apply(const DropPackets& f, Recording& r, Rng& rng);
std::string apply(const ReorderPackets& f, Recording& r, Rng& rng);
std::string apply(const DuplicatePackets& f, Recording& r, Rng& rng);
std::string apply(const StopLidar& f, Recording& r, Rng& rng);
std::string apply(const CutStart& f, Recording& r, Rng& rng);
// point_faults.cpp: what the packets carry.
std::string apply(const CorruptPoints& f, Recording& r, Rng& rng);
std::string apply(const GroundOnly& f, Recording& r, Rng& rng);
// clock_faults.cpp
std::string apply(const ClockJump& f, Recording& r, Rng& rng);
// imu_faults.cpp
std::string apply(const CutImu& f, Recording& r, Rng& rng);
std::string apply(const RockImu& f, Recording& r, Rng& rng);
// vehicle_faults.cpp: what a vehicle meets on the road.
std::string apply(const LidarReboot& f, Recording& r, Rng& rng);
std::string apply(const DifopChange& f, Recording& r, Rng& rng);
std::string apply(const Pothole& f, Recording& r, Rng& rng);
std::string apply(const StuckAzimuth& f, Recording& r, Rng& rng);
std::string apply(const SecondSender& f, Recording& r, Rng& rng);

}  // namespace liod::fault
