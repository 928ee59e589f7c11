#pragma once
/// CRC-8/SAE-J1850 and the frame checksum of the rig's CAN layout.

#include <cstddef>
#include <cstdint>

namespace nimble::can {

/// CRC-8/SAE-J1850: polynomial 0x1D, initial value 0xFF, final XOR 0xFF, not reflected.
/// Check value: crc8_sae_j1850("123456789") == 0x4B.
uint8_t crc8_sae_j1850(const uint8_t* data, std::size_t length_bytes);

/// Checksum of one rig frame: CRC-8/SAE-J1850 over the 11-bit identifier as two bytes,
/// little-endian (id & 0xFF, id >> 8), followed by the payload bytes before the CRC byte
/// (`payload_bytes`: 7 for an 8-byte frame). Covering the identifier detects a payload that
/// arrives under another frame's identifier.
uint8_t frame_crc(uint32_t id, const uint8_t* payload, std::size_t payload_bytes);

}  // namespace nimble::can
