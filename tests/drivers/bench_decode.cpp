// Decoding throughput: RS-Helios packets -> sweeps (MSOP decode + sweep assembly), one core.
// Target: > 150,000 packets/s (100x the 1500 packets/s line rate of a single-return Helios).
#include <benchmark/benchmark.h>

#include <filesystem>

#include "liod/drivers/pcap_reader.hpp"
#include "liod/drivers/rs_helios.hpp"
#include "test_support.hpp"

namespace liod::drivers {
namespace {

void run_decoder(benchmark::State& state, HeliosOptions options, const std::vector<std::vector<std::uint8_t>>& packets) {
  Scan recycled;
  std::size_t points = 0;
  RsHeliosDecoder decoder(std::move(options), [&](Scan& scan, const SweepInfo&) {
    points += scan.points.size();
    std::swap(scan, recycled);
  });
  std::int64_t fed = 0;
  for (auto _ : state) {
    for (const auto& p : packets) decoder.feed(p);
    fed += static_cast<std::int64_t>(packets.size());
  }
  benchmark::DoNotOptimize(points);
  state.counters["packets_per_s"] = benchmark::Counter(static_cast<double>(fed), benchmark::Counter::kIsRate);
  state.counters["points_per_packet"] =
      static_cast<double>(decoder.stats().points) / static_cast<double>(std::max<std::uint64_t>(1, decoder.stats().msop));
}

void BM_Decode16PRealPackets(benchmark::State& state) {
  const auto dir = test::robosense_dir();
  if (!std::filesystem::exists(dir / "helios16p_5rev.pcap")) {
    state.SkipWithError("shared RoboSense data not found");
    return;
  }
  std::vector<std::vector<std::uint8_t>> packets;
  PcapReader reader(dir / "helios16p_5rev.pcap");
  reader.set_port_filter({6699});
  UdpDatagram d;
  while (reader.next(d)) packets.emplace_back(d.payload.begin(), d.payload.end());
  HeliosOptions o;
  o.model = HeliosModel::Helios16P;
  o.angles = load_angles_csv(dir / "helios16p_angles.csv");
  // Replaying the same 750 packets in a loop makes the clock jump back each pass; the sweep
  // assembler treats that as a gap and cuts a sweep, which is fine for a throughput figure.
  run_decoder(state, o, packets);
}
BENCHMARK(BM_Decode16PRealPackets)->Unit(benchmark::kMicrosecond);

void BM_Decode5515SyntheticSingleReturn(benchmark::State& state) {
  // One revolution at 10 Hz, every slot a valid return (worst case: 384 points per packet).
  std::vector<std::vector<std::uint8_t>> packets;
  for (std::size_t i = 0; i < 150; ++i) {
    std::array<test::SyntheticBlock, 12> blocks{};
    for (std::size_t k = 0; k < 12; ++k) {
      blocks[k].azimuth = static_cast<std::uint16_t>((20 * (12 * i + k)) % 36000);
      for (std::size_t s = 0; s < 32; ++s) {
        blocks[k].raw_distance[s] = static_cast<std::uint16_t>(400 + (i * 131 + k * 17 + s * 29) % 8000);
        blocks[k].intensity[s] = static_cast<std::uint8_t>(s + k);
      }
    }
    const auto t_us = static_cast<std::int64_t>(1'700'000'000'000'000LL + static_cast<std::int64_t>(i) * 667);
    packets.push_back(test::make_msop(t_us, static_cast<std::uint32_t>(i), blocks));
  }
  HeliosOptions o;
  o.model = HeliosModel::Helios5515;
  std::vector<double> vert(32);
  std::vector<double> horiz(32);
  for (std::size_t i = 0; i < 32; ++i) {
    vert[i] = 14.94 - 2.2 * static_cast<double>(i);
    horiz[i] = i % 2 ? 3.6 : -4.0;
  }
  o.angles = AngleTable{vert, horiz};
  run_decoder(state, o, packets);
}
BENCHMARK(BM_Decode5515SyntheticSingleReturn)->Unit(benchmark::kMicrosecond);

void BM_ReadPcapAndDecode16P(benchmark::State& state) {
  const auto dir = test::robosense_dir();
  if (!std::filesystem::exists(dir / "helios16p_5rev.pcap")) {
    state.SkipWithError("shared RoboSense data not found");
    return;
  }
  HeliosOptions o;
  o.model = HeliosModel::Helios16P;
  o.angles = load_angles_csv(dir / "helios16p_angles.csv");
  std::int64_t fed = 0;
  for (auto _ : state) {
    RsHeliosDecoder decoder(o, [](Scan&, const SweepInfo&) {});
    PcapReader reader(dir / "helios16p_5rev.pcap");
    UdpDatagram d;
    while (reader.next(d)) decoder.feed(d.payload, d.capture_time_ns);
    fed += static_cast<std::int64_t>(reader.stats().delivered);
  }
  state.counters["packets_per_s"] = benchmark::Counter(static_cast<double>(fed), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ReadPcapAndDecode16P)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace liod::drivers
