#include "liod/drivers/pcap_reader.hpp"
#include "liod/drivers/c_file.hpp"

#include <algorithm>
#include <cinttypes>
#include <cstring>
#include <utility>

#include "link_frame.hpp"
#include "liod/drivers/byte_order.hpp"
#include "liod/drivers/input_error.hpp"

namespace liod::drivers {
namespace {

constexpr std::uint32_t kPcapMagicMicros = 0xA1B2C3D4;
constexpr std::uint32_t kPcapMagicNanos = 0xA1B23C4D;
constexpr std::uint32_t kNgSectionHeader = 0x0A0D0D0A;
constexpr std::uint32_t kNgByteOrderMagic = 0x1A2B3C4D;
constexpr std::uint32_t kNgInterfaceDescription = 1;
constexpr std::uint32_t kNgObsoletePacket = 2;
constexpr std::uint32_t kNgSimplePacket = 3;
constexpr std::uint32_t kNgEnhancedPacket = 6;
// No link layer we parse carries frames this large (an IPv4 datagram is at most 64 KiB); a bigger
// length means a corrupt file, and refusing it keeps a corrupt length field from allocating
// gigabytes. The limit holds whatever snaplen a classic file's header claims, as in Wireshark.
constexpr std::uint32_t kMaxRecordBytes = 256 * 1024;
constexpr std::uint32_t kMaxBlockBytes = kMaxRecordBytes + 4096;

}  // namespace

/// pcapng per-interface state (IDB): link type and timestamp units. Not in the anonymous
/// namespace: PcapReader::Impl, whose class has external linkage, holds them.
struct NgInterface {
  std::uint32_t link_type = 0;
  std::uint32_t snaplen = 0;
  bool resolution_is_power_of_two = false;
  std::uint8_t resolution_exponent = 6;  // default if_tsresol: 10^-6 s
  std::int64_t offset_s = 0;             // if_tsoffset

  // Unsigned arithmetic throughout: a corrupt timestamp or offset must wrap, not be undefined.
  [[nodiscard]] std::int64_t to_ns(std::uint64_t units) const noexcept {
    std::uint64_t ns = 0;
    if (resolution_is_power_of_two) {
      const unsigned k = resolution_exponent;
      const std::uint64_t whole = k >= 64 ? 0 : units >> k;
      std::uint64_t frac = k >= 64 ? units : units & ((std::uint64_t{1} << k) - 1);
      unsigned shift = k;
      if (shift > 30) {  // keep frac * 1e9 inside 64 bits
        const unsigned drop = shift - 30;
        frac = drop >= 64 ? 0 : frac >> drop;  // at 2^-94 s per unit or finer, any count is < 1 ns
        shift = 30;
      }
      ns = whole * 1'000'000'000ULL + ((frac * 1'000'000'000ULL) >> shift);
    } else {
      const unsigned n = resolution_exponent;
      std::uint64_t scale = 1;
      if (n <= 9) {
        for (unsigned i = n; i < 9; ++i) scale *= 10;
        ns = units * scale;
      } else {
        for (unsigned i = 9; i < n && i < 28; ++i) scale *= 10;
        ns = units / scale;
      }
    }
    return static_cast<std::int64_t>(ns + static_cast<std::uint64_t>(offset_s) * 1'000'000'000ULL);
  }
};

struct PcapReader::Impl {
  std::string path;
  CFile file;
  CaptureFormat format = CaptureFormat::Pcap;
  bool big_endian = false;
  // classic pcap
  bool nanosecond_stamps = false;
  std::uint32_t link_type = 0;
  // pcapng
  std::vector<NgInterface> interfaces;

  std::vector<std::uint8_t> buffer;
  std::uint64_t offset = 0;  // bytes consumed, for error messages
  std::vector<std::uint16_t> ports;
  PcapStats stats;
  std::string error;
  bool finished = false;

  std::size_t read(void* dst, std::size_t n) {
    const std::size_t got = std::fread(dst, 1, n, file.get());
    offset += got;
    return got;
  }

  void stop(std::string why) {
    error = path + ": " + std::move(why);
    finished = true;
  }

  void stop_truncated(std::size_t wanted, std::size_t got, std::uint64_t start) {
    stats.truncated_file = 1;
    stop("file ends inside a record (record starting at byte " + std::to_string(start) + " needs " +
         std::to_string(wanted) + " more bytes, only " + std::to_string(got) + " present)");
  }

  void open_classic(const std::uint8_t* header);
  void open_ng(const std::uint8_t* first8);
  bool next_classic(UdpDatagram& out);
  bool next_ng(UdpDatagram& out);
  bool read_ng_block(std::uint32_t& type, std::size_t& body_size);
  void parse_section_header(std::size_t body_size);
  void parse_interface(std::size_t body_size);
  bool deliver(std::uint32_t link, const std::uint8_t* frame, std::size_t caplen, std::size_t origlen,
               std::int64_t time_ns, UdpDatagram& out);
};

PcapReader::PcapReader(const std::filesystem::path& path) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.path = path.string();
  s.file.reset(std::fopen(s.path.c_str(), "rb"));
  if (!s.file) throw InputError(s.path, 0, std::string("cannot open capture file: ") + std::strerror(errno));
  std::setvbuf(s.file.get(), nullptr, _IOFBF, 1 << 20);

  std::uint8_t head[24];
  const std::size_t got = s.read(head, 8);
  if (got < 8) throw InputError(s.path, 0, "not a pcap or pcapng file (shorter than a file header)");
  const std::uint32_t magic_le = load_le32(head);
  if (magic_le == kNgSectionHeader) {
    s.open_ng(head);
    return;
  }
  if (magic_le == kPcapMagicMicros || magic_le == kPcapMagicNanos || load_be32(head) == kPcapMagicMicros ||
      load_be32(head) == kPcapMagicNanos) {
    if (s.read(head + 8, 16) < 16) throw InputError(s.path, 0, "pcap file header is cut short");
    s.open_classic(head);
    return;
  }
  char hex[16];
  std::snprintf(hex, sizeof hex, "0x%08" PRIx32, load_be32(head));
  throw InputError(s.path, 0, std::string("not a pcap or pcapng file (first bytes ") + hex + ")");
}

PcapReader::~PcapReader() = default;
PcapReader::PcapReader(PcapReader&&) noexcept = default;
PcapReader& PcapReader::operator=(PcapReader&&) noexcept = default;

void PcapReader::set_port_filter(std::vector<std::uint16_t> ports) { impl_->ports = std::move(ports); }
const PcapStats& PcapReader::stats() const noexcept { return impl_->stats; }
const std::string& PcapReader::error() const noexcept { return impl_->error; }
CaptureFormat PcapReader::format() const noexcept { return impl_->format; }

bool PcapReader::next(UdpDatagram& out) {
  Impl& s = *impl_;
  if (s.finished) return false;
  return s.format == CaptureFormat::Pcap ? s.next_classic(out) : s.next_ng(out);
}

void PcapReader::Impl::open_classic(const std::uint8_t* header) {
  format = CaptureFormat::Pcap;
  const std::uint32_t magic = load_le32(header);
  big_endian = !(magic == kPcapMagicMicros || magic == kPcapMagicNanos);
  nanosecond_stamps = load32(header, big_endian) == kPcapMagicNanos;
  const std::uint16_t major = load16(header + 4, big_endian);
  if (major != 2) throw InputError(path, 0, "unsupported pcap version " + std::to_string(major));
  // The top bits of the link-type word carry FCS information (pcap spec "LinkType and
  // additional information"); any FCS lies after the IP datagram and is ignored anyway.
  link_type = load32(header + 20, big_endian) & 0x03FFFFFFu;
  if (!detail::is_supported_link_type(link_type))
    throw InputError(path, 0, "unsupported pcap link type " + std::to_string(link_type) +
                                  " (supported: Ethernet, Linux SLL/SLL2, raw IPv4)");
}

bool PcapReader::Impl::next_classic(UdpDatagram& out) {
  for (;;) {
    const std::uint64_t start = offset;
    std::uint8_t rh[16];
    const std::size_t got = read(rh, sizeof rh);
    if (got == 0) {
      finished = true;
      return false;
    }
    if (got < sizeof rh) {
      stop_truncated(sizeof rh, got, start);
      return false;
    }
    const std::uint32_t ts_sec = load32(rh, big_endian);
    const std::uint32_t ts_frac = load32(rh + 4, big_endian);
    const std::uint32_t caplen = load32(rh + 8, big_endian);
    const std::uint32_t origlen = load32(rh + 12, big_endian);
    if (caplen > kMaxRecordBytes) {
      ++stats.malformed;
      stop("corrupt record header at byte " + std::to_string(start) + " (captured length " +
           std::to_string(caplen) + " exceeds " + std::to_string(kMaxRecordBytes) + "); stopped reading");
      return false;
    }
    if (buffer.size() < caplen) buffer.resize(caplen);
    const std::size_t data = read(buffer.data(), caplen);
    if (data < caplen) {
      stop_truncated(caplen, data, start);
      return false;
    }
    ++stats.records;
    const std::int64_t time_ns = static_cast<std::int64_t>(ts_sec) * 1'000'000'000LL +
                                 static_cast<std::int64_t>(ts_frac) * (nanosecond_stamps ? 1 : 1000);
    if (deliver(link_type, buffer.data(), caplen, origlen, time_ns, out)) return true;
  }
}

bool PcapReader::Impl::deliver(std::uint32_t link, const std::uint8_t* frame, std::size_t caplen,
                               std::size_t origlen, std::int64_t time_ns, UdpDatagram& out) {
  if (caplen < origlen) {
    ++stats.truncated_record;
    return false;
  }
  switch (detail::parse_frame(link, frame, caplen, out)) {
    case detail::FrameResult::Udp:
      break;
    case detail::FrameResult::NotIpv4:
      ++stats.not_ipv4;
      return false;
    case detail::FrameResult::NotUdp:
      ++stats.not_udp;
      return false;
    case detail::FrameResult::Fragment:
      ++stats.ip_fragment;
      return false;
    case detail::FrameResult::Malformed:
      ++stats.malformed;
      return false;
    case detail::FrameResult::UnsupportedLink:
      ++stats.unsupported_link;
      return false;
  }
  if (!ports.empty() && std::find(ports.begin(), ports.end(), out.dst_port) == ports.end()) {
    ++stats.port_filtered;
    return false;
  }
  out.capture_time_ns = time_ns;
  ++stats.delivered;
  return true;
}

// ---- pcapng -------------------------------------------------------------------------------------

void PcapReader::Impl::open_ng(const std::uint8_t* first8) {
  format = CaptureFormat::PcapNg;
  std::uint8_t bom[4];
  if (read(bom, 4) < 4) throw InputError(path, 0, "pcapng section header is cut short");
  if (load_le32(bom) == kNgByteOrderMagic) {
    big_endian = false;
  } else if (load_be32(bom) == kNgByteOrderMagic) {
    big_endian = true;
  } else {
    throw InputError(path, 0, "pcapng section header has no valid byte-order magic");
  }
  const std::uint32_t total = load32(first8 + 4, big_endian);
  if (total < 28 || total % 4 != 0 || total > kMaxBlockBytes)
    throw InputError(path, 0, "pcapng section header has an invalid length " + std::to_string(total));
  const std::size_t rest = total - 12;
  buffer.resize(std::max<std::size_t>(rest, 2048));
  if (read(buffer.data(), rest) < rest) throw InputError(path, 0, "pcapng section header is cut short");
  if (load32(buffer.data() + rest - 4, big_endian) != total)
    throw InputError(path, 0, "pcapng section header lengths disagree");
  parse_section_header(rest - 4);
}

void PcapReader::Impl::parse_section_header(std::size_t body_size) {
  // body (after the byte-order magic): major u16, minor u16, section length i64, options
  if (body_size < 12) throw InputError(path, 0, "pcapng section header too short");
  const std::uint16_t major = load16(buffer.data(), big_endian);
  if (major != 1) throw InputError(path, 0, "unsupported pcapng version " + std::to_string(major));
  interfaces.clear();  // interface ids are per section
}

void PcapReader::Impl::parse_interface(std::size_t body_size) {
  NgInterface itf;
  if (body_size < 8) {
    ++stats.malformed;
    interfaces.push_back(itf);  // keep the ids of later interfaces right
    return;
  }
  const std::uint8_t* b = buffer.data();
  itf.link_type = load16(b, big_endian);
  itf.snaplen = load32(b + 4, big_endian);
  std::size_t pos = 8;
  while (pos + 4 <= body_size) {
    const std::uint16_t code = load16(b + pos, big_endian);
    const std::uint16_t len = load16(b + pos + 2, big_endian);
    pos += 4;
    if (code == 0 || pos + len > body_size) break;  // opt_endofopt or a broken option list
    if (code == 9 && len >= 1) {                    // if_tsresol
      itf.resolution_is_power_of_two = (b[pos] & 0x80u) != 0;
      itf.resolution_exponent = static_cast<std::uint8_t>(b[pos] & 0x7Fu);
    } else if (code == 14 && len >= 8) {  // if_tsoffset, seconds
      const std::uint64_t hi = load32(b + pos, big_endian);
      const std::uint64_t lo = load32(b + pos + 4, big_endian);
      itf.offset_s = static_cast<std::int64_t>(big_endian ? (hi << 32) | lo : (lo << 32) | hi);
    }
    pos += (len + 3u) & ~std::size_t{3};
  }
  interfaces.push_back(itf);
}

bool PcapReader::Impl::read_ng_block(std::uint32_t& type, std::size_t& body_size) {
  const std::uint64_t start = offset;
  std::uint8_t head[12];
  const std::size_t got = read(head, 8);
  if (got == 0) {
    finished = true;
    return false;
  }
  if (got < 8) {
    stop_truncated(8, got, start);
    return false;
  }
  type = load32(head, big_endian);
  std::size_t header_bytes = 8;
  if (type == kNgSectionHeader) {  // a new section may switch byte order
    const std::size_t bom = read(head + 8, 4);
    if (bom < 4) {
      stop_truncated(4, bom, start);
      return false;
    }
    if (load_le32(head + 8) == kNgByteOrderMagic) {
      big_endian = false;
    } else if (load_be32(head + 8) == kNgByteOrderMagic) {
      big_endian = true;
    } else {
      ++stats.malformed;
      stop("pcapng section header at byte " + std::to_string(start) + " has no byte-order magic");
      return false;
    }
    header_bytes = 12;
  }
  const std::uint32_t total = load32(head + 4, big_endian);
  if (total < header_bytes + 4 || total % 4 != 0 || total > kMaxBlockBytes) {
    ++stats.malformed;
    stop("corrupt pcapng block at byte " + std::to_string(start) + " (length " + std::to_string(total) +
         "); stopped reading");
    return false;
  }
  const std::size_t rest = total - header_bytes;
  if (buffer.size() < rest) buffer.resize(rest);
  const std::size_t data = read(buffer.data(), rest);
  if (data < rest) {
    stop_truncated(rest, data, start);
    return false;
  }
  if (load32(buffer.data() + rest - 4, big_endian) != total) {
    ++stats.malformed;
    stop("corrupt pcapng block at byte " + std::to_string(start) + " (leading and trailing lengths differ)");
    return false;
  }
  body_size = rest - 4;
  return true;
}

bool PcapReader::Impl::next_ng(UdpDatagram& out) {
  for (;;) {
    std::uint32_t type = 0;
    std::size_t body = 0;
    if (!read_ng_block(type, body)) return false;
    const std::uint8_t* b = buffer.data();
    switch (type) {
      case kNgSectionHeader:
        if (body < 12 || load16(b, big_endian) != 1) {
          ++stats.malformed;
          stop("unsupported pcapng section at byte " + std::to_string(offset));
          return false;
        }
        interfaces.clear();
        break;
      case kNgInterfaceDescription:
        parse_interface(body);
        break;
      case kNgEnhancedPacket:
      case kNgObsoletePacket: {
        if (body < 20) {
          ++stats.malformed;
          break;
        }
        const bool enhanced = type == kNgEnhancedPacket;
        const std::uint32_t itf_id = enhanced ? load32(b, big_endian) : load16(b, big_endian);
        const std::uint64_t ts = (std::uint64_t{load32(b + 4, big_endian)} << 32) | load32(b + 8, big_endian);
        const std::uint32_t caplen = load32(b + 12, big_endian);
        const std::uint32_t origlen = load32(b + 16, big_endian);
        ++stats.records;
        if (itf_id >= interfaces.size() || caplen > body - 20) {
          ++stats.malformed;
          break;
        }
        const NgInterface& itf = interfaces[itf_id];
        if (!detail::is_supported_link_type(itf.link_type)) {
          ++stats.unsupported_link;
          break;
        }
        if (deliver(itf.link_type, b + 20, caplen, origlen, itf.to_ns(ts), out)) return true;
        break;
      }
      case kNgSimplePacket: {
        // No timestamp and no captured length: the frame is the body minus padding, cut to snaplen.
        if (body < 4 || interfaces.empty()) {
          ++stats.malformed;
          break;
        }
        ++stats.records;
        const std::uint32_t origlen = load32(b, big_endian);
        std::size_t caplen = std::min<std::size_t>(origlen, body - 4);
        if (interfaces[0].snaplen != 0) caplen = std::min<std::size_t>(caplen, interfaces[0].snaplen);
        if (!detail::is_supported_link_type(interfaces[0].link_type)) {
          ++stats.unsupported_link;
          break;
        }
        if (deliver(interfaces[0].link_type, b + 4, caplen, origlen, 0, out)) return true;
        break;
      }
      default:
        break;  // statistics, name resolution, custom blocks: nothing we need
    }
  }
}

}  // namespace liod::drivers
