#include "liod/daemon/decode_command.hpp"

#include <bit>
#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <ostream>
#include <string>

#include "liod/drivers/input_error.hpp"
#include "liod/drivers/pcap_reader.hpp"
#include "liod/drivers/pcd_io.hpp"
#include "liod/drivers/rs_helios.hpp"

namespace liod {
namespace {

using drivers::HeliosModel;

constexpr int kInputError = 1;
constexpr int kOptionError = 2;

std::optional<HeliosModel> choose_model(const DecodeOptions& o, const std::optional<drivers::AngleTable>& angles,
                                        std::ostream& out) {
  if (!o.model.empty()) {
    const auto model = drivers::parse_helios_model(o.model);
    if (!model) out << "error: unknown model '" << o.model << "' (use helios5515 or helios16p)\n";
    return model;
  }
  if (!angles) return HeliosModel::Helios5515;
  if (angles->size() == 16) return HeliosModel::Helios16P;
  if (angles->size() == 32) return HeliosModel::Helios5515;
  out << "error: " << o.angles_csv << " has " << angles->size()
      << " rows; cannot infer the model (expected 16 or 32), pass --model\n";
  return std::nullopt;
}

std::string sweep_line(const Scan& scan, const drivers::SweepInfo& info) {
  std::uint32_t rings = 0;
  for (const LidarPoint& p : scan.points) rings |= (p.ring < 32 ? (1U << p.ring) : 0U);
  char line[256];
  std::snprintf(line, sizeof line,
                "sweep %06" PRIu64 "  start %.6f  points %6zu  rings %2d/%u  azimuth %6.2f..%6.2f (%5.1f deg)  "
                "duration %.4f s%s%s%s",
                scan.sequence, scan.start_time, scan.points.size(), std::popcount(rings),
                static_cast<unsigned>(scan.beam_count), info.first_azimuth * 0.01, info.last_azimuth * 0.01,
                info.azimuth_coverage_deg, scan.end_time - scan.start_time, info.ended_by_gap ? "  [cut by time gap]" : "",
                info.truncated ? "  [cut at the size cap]" : "", info.flushed ? "  [partial, end of file]" : "");
  return line;
}

void print_counts(const drivers::HeliosStats& h, const drivers::PcapStats& p, std::ostream& out) {
  out << "packets: msop " << h.msop << ", difop " << h.difop << ", rejected " << h.rejected()
      << " (wrong_size " << h.wrong_size << ", bad_magic " << h.bad_magic << ", bad_timestamp " << h.bad_timestamp
      << ", bad_azimuth " << h.bad_azimuth << ", broken_first_block " << h.broken_first_block << ", no_calibration "
      << h.no_calibration << "), cut_at_broken_block " << h.broken_block_flag << ", lost " << h.lost_packets
      << ", difop_angles_rejected " << h.difop_angles_rejected << "; capture: records " << p.records << ", udp "
      << p.delivered << ", other_ports " << p.port_filtered << ", dropped " << p.dropped() << " (truncated_record "
      << p.truncated_record << ", ip_fragment " << p.ip_fragment << ", not_ipv4 " << p.not_ipv4 << ", not_udp "
      << p.not_udp << ", malformed " << p.malformed << ", unsupported_link " << p.unsupported_link
      << "), truncated_file " << p.truncated_file << "; sweeps " << h.sweeps << " (+" << h.partial_sweeps_dropped
      << " partial dropped, " << h.truncated_sweeps << " cut at the size cap)\n";
}

}  // namespace

int run_decode(const DecodeOptions& o, std::ostream& out) {
  if (o.pcap.empty()) {
    out << "error: no capture file given (--pcap)\n";
    return kOptionError;
  }
  if (!(o.min_range_m >= 0.0 && o.max_range_m > o.min_range_m)) {
    out << "error: invalid range limits " << o.min_range_m << " .. " << o.max_range_m << " m\n";
    return kOptionError;
  }
  try {
    std::optional<drivers::AngleTable> angles;
    if (!o.angles_csv.empty()) angles = drivers::load_angles_csv(o.angles_csv);
    const std::optional<HeliosModel> model = choose_model(o, angles, out);
    if (!model) return kOptionError;

    drivers::PcapReader reader(o.pcap);
    if (o.msop_port != 0 && o.difop_port != 0) reader.set_port_filter({o.msop_port, o.difop_port});
    if (!o.out_dir.empty()) std::filesystem::create_directories(o.out_dir);

    drivers::HeliosOptions options;
    options.model = *model;
    options.angles = angles;
    options.split_azimuth_deg = o.split_azimuth_deg;
    options.emit_partial_sweep_on_flush = o.emit_partial_last;
    options.msop.min_range_m = static_cast<float>(o.min_range_m);
    options.msop.max_range_m = static_cast<float>(o.max_range_m);
    options.msop.time_source = o.arrival_time ? drivers::TimeSource::ArrivalTime : drivers::TimeSource::SensorClock;

    out << "decoding " << o.pcap << " as " << drivers::to_string(*model)
        << (angles ? " with angles from " + o.angles_csv : std::string(" (angles from DIFOP only)")) << '\n';
    drivers::RsHeliosDecoder decoder(options, [&](Scan& scan, const drivers::SweepInfo& info) {
      out << sweep_line(scan, info) << '\n';
      if (!o.out_dir.empty()) {
        char name[32];
        std::snprintf(name, sizeof name, "sweep_%06" PRIu64 ".pcd", scan.sequence);
        drivers::write_pcd_binary(std::filesystem::path(o.out_dir) / name, scan);
      }
    });
    drivers::UdpDatagram datagram;
    while (reader.next(datagram)) decoder.feed(datagram.payload, datagram.capture_time_ns);
    decoder.flush();

    const drivers::HeliosStats stats = decoder.stats();
    print_counts(stats, reader.stats(), out);
    if (!reader.error().empty()) out << "warning: " << reader.error() << '\n';
    if (stats.msop == 0 && stats.no_calibration > 0) {
      out << "error: no angle calibration for any of the " << stats.no_calibration
          << " MSOP packets (no valid DIFOP in the capture): pass --angles\n";
      return kInputError;
    }
    return 0;
  } catch (const drivers::InputError& e) {
    out << "error: " << e.what() << '\n';
    return kInputError;
  } catch (const std::filesystem::filesystem_error& e) {
    out << "error: " << e.what() << '\n';
    return kInputError;
  }
}

}  // namespace liod
