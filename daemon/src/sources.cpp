#include "liod/daemon/sources.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "liod/drivers/can_imu.hpp"
#include "liod/drivers/imu_csv.hpp"
#include "liod/drivers/mtdata2.hpp"
#include "liod/drivers/rs_helios.hpp"
#include "liod/drivers/serial_port.hpp"
#include "liod/drivers/time_sync.hpp"
#include "liod/drivers/udp_receiver.hpp"

namespace liod {

bool PaceClock::wait_until(std::int64_t data_ns, const std::atomic<bool>& stop, const std::function<void()>& heartbeat) const {
  if (pace <= 0.0) return !stop.load(std::memory_order_relaxed);
  const std::int64_t now = steady_ns();
  // In double: a corrupt capture time may be anywhere in the int64 range.
  const double data_offset = (static_cast<double>(data_ns) - static_cast<double>(data_start_ns)) / pace;
  const double ahead = static_cast<double>(host_start_steady_ns) + data_offset +
                       static_cast<double>(shift_ns_.load(std::memory_order_relaxed)) - static_cast<double>(now);
  if (!std::isfinite(ahead) || std::abs(ahead) > static_cast<double>(max_offset_ns)) {
    // Due now from here on. The other source moves it back if its data did not jump.
    const double shift = static_cast<double>(now - host_start_steady_ns) - data_offset;
    const double limit = 4e18;
    shift_ns_.store(static_cast<std::int64_t>(std::clamp(shift, -limit, limit)), std::memory_order_relaxed);
    if (reanchors_.fetch_add(1, std::memory_order_relaxed) < 5) {
      spdlog::warn("replay: data time {:.3f} s is {:.1f} s from its pace; the pace clock continues from it",
                   static_cast<double>(data_ns) * 1e-9, ahead * 1e-9);
    }
    return !stop.load(std::memory_order_relaxed);
  }
  const auto due = now + static_cast<std::int64_t>(ahead);
  for (;;) {
    if (stop.load(std::memory_order_relaxed)) return false;
    const std::int64_t left = due - steady_ns();
    if (left <= 0) return true;
    heartbeat();
    std::this_thread::sleep_for(std::chrono::nanoseconds(std::min<std::int64_t>(left, 50000000)));
  }
}

std::int64_t first_pcap_time_ns(const std::string& path, const std::vector<std::uint16_t>& ports) {
  drivers::PcapReader reader(path);
  reader.set_port_filter(ports);
  drivers::UdpDatagram d;
  return reader.next(d) ? d.capture_time_ns : 0;
}

std::int64_t first_imu_time_ns(const std::string& path) {
  drivers::ImuCsvReader reader(path);
  ImuSample s;
  return reader.next(s) ? static_cast<std::int64_t>(std::llround(s.time * 1e9)) : 0;
}

namespace {

/// Logs once which sender the LiDAR's datagrams are taken from, and once that others are refused.
void report_source(const drivers::SourceFilter& filter, bool& reported_lock, bool& reported_other) {
  if (!reported_lock && filter.source() != 0) {
    spdlog::info("LiDAR: taking datagrams from {} only (the first RS-Helios sender; set "
                 "drivers.lidar.source_address to choose)", drivers::format_ipv4(filter.source()));
    reported_lock = true;
  }
  if (!reported_other && filter.refused() > 0) {
    spdlog::warn("LiDAR: dropping datagrams from {}, not the LiDAR at {} (this and any other sender: counted in "
                 "health lidar.transport_refused, not logged again)",
                 drivers::format_ipv4(filter.last_refused()), drivers::format_ipv4(filter.source()));
    reported_other = true;
  }
}

}  // namespace

// ---- files -------------------------------------------------------------------------------------
PcapLidarSource::PcapLidarSource(std::string path, std::vector<std::uint16_t> ports, std::shared_ptr<const PaceClock> pace)
    : path_(std::move(path)), ports_(std::move(ports)), pace_(std::move(pace)) {}

void PcapLidarSource::run(LidarOutput& out, const std::atomic<bool>& stop) {
  drivers::PcapReader reader(path_);
  reader.set_port_filter(ports_);
  drivers::UdpDatagram d;
  std::uintmax_t bytes = 0;
  // A capture may hold every sender on the ports (tcpdump): taken as the socket would take them.
  drivers::SourceFilter filter(0, drivers::is_helios_packet);
  bool reported_lock = true;  // a replay names no sender unless another one is refused
  bool reported_other = false;
  while (reader.next(d)) {
    if (!pace_->wait_until(d.capture_time_ns, stop, [&] { out.heartbeat(); })) break;
    bytes += d.payload.size() + 58;
    bytes_.store(bytes, std::memory_order_relaxed);
    if (!filter.accept(d.src_ip, d.payload)) {
      out.transport.refused.store(filter.refused(), std::memory_order_relaxed);
      report_source(filter, reported_lock, reported_other);
      continue;
    }
    out.packet(d.payload, d.capture_time_ns, d.dst_port);
  }
  stats_ = reader.stats();
  error_ = reader.error();
}

CsvImuSource::CsvImuSource(std::string path, std::shared_ptr<const PaceClock> pace)
    : path_(std::move(path)), pace_(std::move(pace)) {}

void CsvImuSource::run(ImuOutput& out, const std::atomic<bool>& stop) {
  drivers::ImuCsvReader reader(path_);
  ImuSample s;
  std::size_t n = 0;
  while (reader.next(s)) {
    if (!pace_->wait_until(to_ns(s.time), stop, [&] { out.heartbeat(); })) break;
    out.sample(s);
    if ((++n & 63) == 0) out.heartbeat();
  }
}

// ---- UDP LiDAR ---------------------------------------------------------------------------------

UdpLidarSource::UdpLidarSource(const Config& config) : config_(config) {}

std::string UdpLidarSource::describe() const {
  const auto& d = config_.drivers.lidar;
  return "UDP " + (d.multicast_group.empty() ? d.bind_address : d.multicast_group) + ":" +
         std::to_string(config_.lidar.msop_port) + "/" + std::to_string(config_.lidar.difop_port) +
         (d.source_address.empty() ? "" : " from " + d.source_address);
}

void UdpLidarSource::run(LidarOutput& out, const std::atomic<bool>& stop) {
  const auto& d = config_.drivers.lidar;
  drivers::UdpReceiverOptions o;
  o.bind_address = d.bind_address;
  o.ports = {static_cast<std::uint16_t>(config_.lidar.msop_port), static_cast<std::uint16_t>(config_.lidar.difop_port)};
  o.multicast_group = d.multicast_group;
  o.multicast_interface = d.multicast_interface;
  o.source_address = d.source_address;
  // Without a configured address, the sensor is the first sender of an RS-Helios packet: anyone
  // else who reaches the port (the sockets listen on every interface by default) is dropped.
  o.lock_to_first_sender_of = drivers::is_helios_packet;
  o.receive_buffer_bytes = d.receive_buffer_bytes;
  o.batch = d.batch;
  drivers::UdpReceiver receiver(o);
  if (receiver.granted_receive_buffer() < d.receive_buffer_bytes) {
    spdlog::warn("LiDAR: receive buffer {} bytes granted of {} requested (raise net.core.rmem_max or grant CAP_NET_ADMIN)",
                 receiver.granted_receive_buffer(), d.receive_buffer_bytes);
  }
  spdlog::info("LiDAR: listening on {}", describe());
  std::uint64_t reported_kernel_drops = 0;
  bool reported_lock = !d.source_address.empty();
  bool reported_other = false;
  while (!stop.load(std::memory_order_relaxed)) {
    out.heartbeat();
    std::int64_t now = 0;  // one clock read per batch: the batch was taken at once
    receiver.poll(50, [&](const drivers::ReceivedDatagram& dg) {
      if (now == 0) now = drivers::realtime_ns();
      if (dg.kernel_time_ns == 0) {
        out.packet(dg.payload, now, dg.dst_port);
      } else {
        out.packet(dg.payload, dg.kernel_time_ns, dg.dst_port, std::max<std::int64_t>(0, now - dg.kernel_time_ns));
      }
    });
    const auto& rs = receiver.stats();
    out.transport.lost.store(rs.kernel_drops, std::memory_order_relaxed);
    out.transport.refused.store(rs.filtered_source + rs.truncated, std::memory_order_relaxed);
    report_source(receiver.source_filter(), reported_lock, reported_other);
    const auto drops = rs.kernel_drops;
    if (drops > reported_kernel_drops) {
      spdlog::warn("LiDAR: the kernel dropped {} datagrams (receive buffer full)", drops - reported_kernel_drops);
      reported_kernel_drops = drops;
    }
  }
}

// ---- serial MTData2 ----------------------------------------------------------------------------
SerialImuSource::SerialImuSource(const Config& config) : config_(config) {}

std::string SerialImuSource::describe() const {
  return "Xsens MTData2 on " + config_.drivers.imu.serial_device + " at " + std::to_string(config_.drivers.imu.serial_baud);
}

void SerialImuSource::run(ImuOutput& out, const std::atomic<bool>& stop) {
  const auto& c = config_.drivers.imu;
  // Samples are stamped from the IMU's own SampleTimeFine (10 kHz) mapped onto the host clock by
  // the minimum of (host read time - sensor time): serial buffering only ever delays a read, so
  // the minimum is the transfer latency's floor, and the inter-sample spacing stays the sensor's.
  drivers::OffsetTracker offset(static_cast<std::int64_t>(config_.time.offset_window_s * 1e9),
                                static_cast<std::int64_t>(config_.time.jump_threshold_s * 1e9));
  std::int64_t read_time = 0;
  std::uint32_t last_fine = 0;
  std::int64_t fine_wraps = 0;
  bool have_fine = false;
  drivers::xsens::MtData2Parser parser([&](const drivers::xsens::MtData2Sample& m) {
    if (!m.rate_of_turn || !m.acceleration) return;
    std::int64_t t = read_time;
    if (m.sample_time_fine) {
      if (have_fine && *m.sample_time_fine < last_fine && last_fine - *m.sample_time_fine > 0x80000000U) ++fine_wraps;
      last_fine = *m.sample_time_fine;
      have_fine = true;
      const std::int64_t sensor_ns = (fine_wraps * (std::int64_t{1} << 32) + *m.sample_time_fine) * 100000;
      t = sensor_ns + offset.add(read_time, sensor_ns);
    }
    ImuSample s;
    s.time = static_cast<double>(t + out.pps_correction_ns.load(std::memory_order_relaxed)) * 1e-9;
    s.gyro = *m.rate_of_turn;
    s.accel = *m.acceleration;
    if (m.status_word && drivers::xsens::inertial_clipped(*m.status_word)) s.flags |= ImuSample::kSaturated;
    out.sample(s);
  });
  std::vector<std::uint8_t> buffer(4096);
  while (!stop.load(std::memory_order_relaxed)) {
    try {
      drivers::SerialPort port(c.serial_device, c.serial_baud);
      spdlog::info("IMU: reading {}", describe());
      while (!stop.load(std::memory_order_relaxed)) {
        out.heartbeat();
        const std::size_t n = port.read(buffer, 50);
        if (n == 0) continue;
        read_time = drivers::realtime_ns();
        parser.feed(std::span(buffer.data(), n));
        out.transport.lost.store(parser.stats().counter_gaps, std::memory_order_relaxed);
        out.transport.refused.store(parser.stats().bad_checksum + parser.stats().malformed, std::memory_order_relaxed);
      }
    } catch (const std::exception& e) {
      // Unplugged adapter or a device not there yet: retry, never die (the IMU-lost flag and the
      // health message say what is going on).
      spdlog::warn("IMU: {}; retrying in 1 s", e.what());
      for (int i = 0; i < 20 && !stop.load(); ++i) {
        out.heartbeat();
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    }
  }
  const auto& st = parser.stats();
  spdlog::info("IMU serial: {} messages, {} bad checksums, {} malformed, {} bytes skipped, {} counter gaps", st.messages,
               st.bad_checksum, st.malformed, st.skipped_bytes, st.counter_gaps);
}

// ---- SocketCAN ---------------------------------------------------------------------------------
CanImuSource::CanImuSource(const Config& config) : config_(config) {}

std::string CanImuSource::describe() const {
  return std::string("CAN ") + (config_.drivers.imu.can_profile == CanProfile::kJ1939 ? "J1939" : "table") + " on " +
         config_.drivers.imu.can_interface;
}

void CanImuSource::run(ImuOutput& out, const std::atomic<bool>& stop) {
  const auto& c = config_.drivers.imu;
  drivers::CanImuDecoder decoder(c.can_profile, c.j1939_source_address, c.can_signals, 1.5 / config_.imu.rate_hz);
  while (!stop.load(std::memory_order_relaxed)) {
    try {
      drivers::SocketCan can(c.can_interface);
      spdlog::info("IMU: reading {}", describe());
      drivers::CanFrame frame;
      while (!stop.load(std::memory_order_relaxed)) {
        out.heartbeat();
        if (!can.read(frame, 50)) continue;
        auto s = decoder.feed(frame);
        out.transport.lost.store(decoder.stats().unpaired + decoder.stats().stale_axes, std::memory_order_relaxed);
        out.transport.refused.store(decoder.stats().not_available, std::memory_order_relaxed);
        if (s) {
          s->time += static_cast<double>(out.pps_correction_ns.load(std::memory_order_relaxed)) * 1e-9;
          out.sample(*s);
        }
      }
    } catch (const std::exception& e) {
      spdlog::warn("IMU: {}; retrying in 1 s", e.what());
      for (int i = 0; i < 20 && !stop.load(); ++i) {
        out.heartbeat();
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    }
  }
}

std::unique_ptr<LidarSource> make_live_lidar_source(const Config& config) { return std::make_unique<UdpLidarSource>(config); }

std::unique_ptr<ImuSource> make_live_imu_source(const Config& config) {
  switch (config.drivers.imu.transport) {
    case ImuTransport::kSerial: return std::make_unique<SerialImuSource>(config);
    case ImuTransport::kCan: return std::make_unique<CanImuSource>(config);
    case ImuTransport::kFile: {
      if (config.drivers.imu.file.empty()) throw ConfigError("drivers.imu.transport is 'file' but drivers.imu.file is empty");
      auto pace = std::make_shared<PaceClock>();
      pace->pace = config.drivers.imu.file_pace;
      pace->data_start_ns = first_imu_time_ns(config.drivers.imu.file);
      pace->host_start_steady_ns = steady_ns();
      return std::make_unique<CsvImuSource>(config.drivers.imu.file, pace);
    }
    case ImuTransport::kNone: return nullptr;
  }
  return nullptr;
}

}  // namespace liod
