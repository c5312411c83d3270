// Fuzz target: the capture-file reader (classic pcap and pcapng, every link layer it parses). The
// input is the file. A file that is not a capture must be refused with InputError; any other file
// must read to its end or to a reported error, handing out only payloads inside what it read.

#include <cstdint>

#include "fuzz_support.hpp"
#include "liod/drivers/input_error.hpp"
#include "liod/drivers/pcap_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using liod::fuzz::require;
  const liod::fuzz::MemoryFile file(data, size);
  try {
    liod::drivers::PcapReader reader(file.path());
    liod::drivers::UdpDatagram d;
    std::uint64_t delivered = 0;
    std::uint64_t payload_bytes = 0;
    while (reader.next(d)) {
      ++delivered;
      payload_bytes += d.payload.size();
      liod::fuzz::touch(d.payload);
    }
    const liod::drivers::PcapStats& s = reader.stats();
    require(s.delivered == delivered, "delivered count differs from the datagrams handed out");
    require(payload_bytes <= size, "payloads larger than the file");
    require(s.truncated_file == 0 || !reader.error().empty(), "a truncated file without an error message");
  } catch (const liod::drivers::InputError&) {
    // Not a capture file (or an unsupported one): refused with a message, as documented.
  }
  return 0;
}
