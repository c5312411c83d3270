#pragma once
// `liod decode`: RS-Helios packets from a capture file -> sweeps, printed and optionally saved as
// binary PCD (sweep_000000.pcd, ...).

#include <cstdint>
#include <iosfwd>
#include <string>

namespace liod {

struct DecodeOptions {
  std::string pcap;        ///< pcap or pcapng file (required)
  std::string angles_csv;  ///< `vertical_deg,horizontal_deg` per channel; a DIFOP table replaces it
  std::string out_dir;     ///< if set, one PCD per sweep is written here (created if missing)
  /// "helios5515" / "helios16p" (see parse_helios_model); empty = infer from the angle CSV's row
  /// count (16 -> 16P, 32 -> 5515), RS-Helios-5515 without a CSV.
  std::string model;
  double split_azimuth_deg = 0.0;
  std::uint16_t msop_port = 6699;   ///< 0 = accept any destination port
  std::uint16_t difop_port = 7788;
  double min_range_m = 0.1;
  double max_range_m = 180.0;
  bool emit_partial_last = false;   ///< also emit the incomplete sweep at the end of the file
  bool arrival_time = false;        ///< stamp points from capture time, not the sensor clock
};

/// Decodes, prints one line per sweep and a final line of packet counts to `out`. Returns 0 on
/// success; 2 for invalid options; 1 when the input cannot be used (unreadable capture or CSV, no
/// calibration for any packet), after printing "error: ..." to `out`. A capture cut mid-record
/// still decodes what precedes the cut and reports it.
int run_decode(const DecodeOptions& options, std::ostream& out);

}  // namespace liod
