#include "can_bridge/crc8.h"

namespace nimble::can {

namespace {

constexpr uint8_t kPolynomial = 0x1D;

/// Continues a CRC-8 (poly 0x1D, MSB first) over `data` without the final XOR.
uint8_t crc8_update(uint8_t crc, const uint8_t* data, std::size_t length_bytes) {
  for (std::size_t i = 0; i < length_bytes; ++i) {
    crc = static_cast<uint8_t>(crc ^ data[i]);
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x80) ? static_cast<uint8_t>((crc << 1) ^ kPolynomial) : static_cast<uint8_t>(crc << 1);
    }
  }
  return crc;
}

}  // namespace

uint8_t crc8_sae_j1850(const uint8_t* data, std::size_t length_bytes) {
  return static_cast<uint8_t>(crc8_update(0xFF, data, length_bytes) ^ 0xFF);
}

uint8_t frame_crc(uint32_t id, const uint8_t* payload, std::size_t payload_bytes) {
  const uint8_t id_bytes[2] = {static_cast<uint8_t>(id & 0xFF), static_cast<uint8_t>((id >> 8) & 0x07)};
  const uint8_t crc = crc8_update(0xFF, id_bytes, sizeof id_bytes);
  return static_cast<uint8_t>(crc8_update(crc, payload, payload_bytes) ^ 0xFF);
}

}  // namespace nimble::can
