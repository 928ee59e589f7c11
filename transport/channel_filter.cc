#include "transport/channel_filter.h"

#include <arpa/inet.h>
#include <dirent.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace nimble::transport {
namespace {

constexpr uint32_t kMagicShort = 0x4c433032;  // "LC02": an LCM message in one datagram
constexpr uint32_t kAccept = 0x40000;         // keep up to 256 KiB of the datagram
const char* const kSelfTest = "LCM_SELF_TEST";

sock_filter stmt(uint16_t code, uint32_t k) { return sock_filter{code, 0, 0, k}; }
sock_filter jump(uint16_t code, uint32_t k, uint8_t jt, uint8_t jf) { return sock_filter{code, jt, jf, k}; }

/// One channel's test: the name and its NUL, compared word by word (big-endian, as BPF loads),
/// the last 1-3 bytes one by one; each mismatch jumps past the block, a full match accepts.
std::vector<sock_filter> channel_block(const std::string& name) {
  std::string bytes = name;
  bytes.push_back('\0');
  std::vector<sock_filter> block;
  const uint32_t base = kLcmHeaderOffset + 8;  // after magic and sequence number
  std::size_t i = 0;
  for (; i + 4 <= bytes.size(); i += 4) {
    const uint32_t word = (static_cast<uint32_t>(static_cast<unsigned char>(bytes[i])) << 24) |
                          (static_cast<uint32_t>(static_cast<unsigned char>(bytes[i + 1])) << 16) |
                          (static_cast<uint32_t>(static_cast<unsigned char>(bytes[i + 2])) << 8) |
                          static_cast<uint32_t>(static_cast<unsigned char>(bytes[i + 3]));
    block.push_back(stmt(BPF_LD | BPF_W | BPF_ABS, base + static_cast<uint32_t>(i)));
    block.push_back(jump(BPF_JMP | BPF_JEQ | BPF_K, word, 0, 0));  // jf filled in below
  }
  for (; i < bytes.size(); ++i) {
    block.push_back(stmt(BPF_LD | BPF_B | BPF_ABS, base + static_cast<uint32_t>(i)));
    block.push_back(jump(BPF_JMP | BPF_JEQ | BPF_K, static_cast<unsigned char>(bytes[i]), 0, 0));
  }
  block.push_back(stmt(BPF_RET | BPF_K, kAccept));
  // A mismatch goes to the instruction after the block.
  for (std::size_t k = 0; k < block.size(); ++k) {
    if (block[k].code == (BPF_JMP | BPF_JEQ | BPF_K)) block[k].jf = static_cast<uint8_t>(block.size() - 1 - k);
  }
  return block;
}

}  // namespace

std::vector<sock_filter> channel_filter_program(const std::set<std::string>& channels) {
  std::vector<std::string> names(channels.begin(), channels.end());
  if (std::find(names.begin(), names.end(), kSelfTest) == names.end()) names.push_back(kSelfTest);
  // Shortest names first: no load of a longer name can run past a short datagram before a
  // shorter name had its chance (a load past the end drops the datagram).
  std::stable_sort(names.begin(), names.end(),
                   [](const std::string& a, const std::string& b) { return a.size() < b.size(); });
  std::vector<sock_filter> prog;
  prog.push_back(stmt(BPF_LD | BPF_W | BPF_ABS, kLcmHeaderOffset));
  prog.push_back(jump(BPF_JMP | BPF_JEQ | BPF_K, kMagicShort, 1, 0));
  prog.push_back(stmt(BPF_RET | BPF_K, kAccept));  // not a short LCM message: keep
  for (const auto& name : names) {
    const std::vector<sock_filter> block = channel_block(name);
    prog.insert(prog.end(), block.begin(), block.end());
  }
  prog.push_back(stmt(BPF_RET | BPF_K, 0));  // an LCM message on a channel not listed: drop
  return prog;
}

std::string attach_channel_filter(int fd, const std::set<std::string>& channels) {
  for (const auto& c : channels) {
    if (c.size() > 100) return "channel name longer than 100 bytes: " + c.substr(0, 20) + "...";
  }
  std::vector<sock_filter> prog = channel_filter_program(channels);
  if (prog.size() > BPF_MAXINSNS) return "too many channels for one socket filter";
  sock_fprog fprog{static_cast<unsigned short>(prog.size()), prog.data()};
  if (::setsockopt(fd, SOL_SOCKET, SO_ATTACH_FILTER, &fprog, sizeof fprog) != 0) {
    return std::string("SO_ATTACH_FILTER: ") + std::strerror(errno);
  }
  return "";
}

std::string detach_channel_filter(int fd) {
  // Linux refuses a socket option shorter than an int (EINVAL) even where, as here, it is unused.
  const int unused = 0;
  if (::setsockopt(fd, SOL_SOCKET, SO_DETACH_FILTER, &unused, sizeof unused) != 0) {
    return std::string("SO_DETACH_FILTER: ") + std::strerror(errno);
  }
  return "";
}

std::set<int> udp_sockets_bound_to(int port) {
  std::set<int> fds;
  DIR* dir = ::opendir("/proc/self/fd");
  if (dir == nullptr) return fds;
  while (const dirent* e = ::readdir(dir)) {
    char* end = nullptr;
    const long fd = std::strtol(e->d_name, &end, 10);
    if (end == e->d_name || *end != '\0' || fd == ::dirfd(dir)) continue;
    int type = 0;
    socklen_t len = sizeof type;
    if (::getsockopt(static_cast<int>(fd), SOL_SOCKET, SO_TYPE, &type, &len) != 0 || type != SOCK_DGRAM) continue;
    sockaddr_in addr{};
    socklen_t alen = sizeof addr;
    if (::getsockname(static_cast<int>(fd), reinterpret_cast<sockaddr*>(&addr), &alen) != 0) continue;
    if (addr.sin_family == AF_INET && ntohs(addr.sin_port) == port) fds.insert(static_cast<int>(fd));
  }
  ::closedir(dir);
  return fds;
}

int udpm_port(const std::string& url) {
  const std::string scheme = "udpm://";
  if (url.compare(0, scheme.size(), scheme) != 0) return url.empty() ? 7667 : -1;
  const std::string rest = url.substr(scheme.size());
  const std::string host_port = rest.substr(0, rest.find('?'));
  const auto colon = host_port.find(':');
  if (colon == std::string::npos) return 7667;
  return std::atoi(host_port.c_str() + colon + 1);
}

std::vector<unsigned char> lcm_short_datagram(const std::string& channel, const std::vector<unsigned char>& payload,
                                              unsigned seqno) {
  std::vector<unsigned char> d;
  const uint32_t magic = htonl(kMagicShort), seq = htonl(seqno);
  d.insert(d.end(), reinterpret_cast<const unsigned char*>(&magic), reinterpret_cast<const unsigned char*>(&magic) + 4);
  d.insert(d.end(), reinterpret_cast<const unsigned char*>(&seq), reinterpret_cast<const unsigned char*>(&seq) + 4);
  d.insert(d.end(), channel.begin(), channel.end());
  d.push_back(0);
  d.insert(d.end(), payload.begin(), payload.end());
  return d;
}

}  // namespace nimble::transport
