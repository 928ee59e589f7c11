#include "can_bridge/error_frame.h"

#include <linux/can/error.h>

#ifndef CAN_ERR_CNT  // added in Linux 5.19 headers; the value is fixed by the kernel ABI
#define CAN_ERR_CNT 0x00000200U
#endif

#include <cstdio>
#include <string>
#include <vector>

namespace nimble::can {

namespace {

/// "a, b, c" of the names whose bit is set in `bits`.
std::string bit_names(uint8_t bits, const std::vector<std::pair<uint8_t, const char*>>& names) {
  std::string out;
  for (const auto& [bit, name] : names) {
    if (bits & bit) {
      if (!out.empty()) out += ", ";
      out += name;
    }
  }
  return out;
}

const char* protocol_location(uint8_t loc) {
  switch (loc) {
    case CAN_ERR_PROT_LOC_SOF: return "start of frame";
    case CAN_ERR_PROT_LOC_ID28_21: return "ID bits 28-21";
    case CAN_ERR_PROT_LOC_ID20_18: return "ID bits 20-18";
    case CAN_ERR_PROT_LOC_SRTR: return "substitute RTR";
    case CAN_ERR_PROT_LOC_IDE: return "identifier extension";
    case CAN_ERR_PROT_LOC_ID17_13: return "ID bits 17-13";
    case CAN_ERR_PROT_LOC_ID12_05: return "ID bits 12-5";
    case CAN_ERR_PROT_LOC_ID04_00: return "ID bits 4-0";
    case CAN_ERR_PROT_LOC_RTR: return "RTR";
    case CAN_ERR_PROT_LOC_RES1: return "reserved bit 1";
    case CAN_ERR_PROT_LOC_RES0: return "reserved bit 0";
    case CAN_ERR_PROT_LOC_DLC: return "data length code";
    case CAN_ERR_PROT_LOC_DATA: return "data section";
    case CAN_ERR_PROT_LOC_CRC_SEQ: return "CRC sequence";
    case CAN_ERR_PROT_LOC_CRC_DEL: return "CRC delimiter";
    case CAN_ERR_PROT_LOC_ACK: return "ACK slot";
    case CAN_ERR_PROT_LOC_ACK_DEL: return "ACK delimiter";
    case CAN_ERR_PROT_LOC_EOF: return "end of frame";
    case CAN_ERR_PROT_LOC_INTERM: return "intermission";
    default: return nullptr;
  }
}

const char* transceiver_state(uint8_t trx) {
  switch (trx) {
    case CAN_ERR_TRX_CANH_NO_WIRE: return "CANH no wire";
    case CAN_ERR_TRX_CANH_SHORT_TO_BAT: return "CANH short to BAT";
    case CAN_ERR_TRX_CANH_SHORT_TO_VCC: return "CANH short to VCC";
    case CAN_ERR_TRX_CANH_SHORT_TO_GND: return "CANH short to GND";
    case CAN_ERR_TRX_CANL_NO_WIRE: return "CANL no wire";
    case CAN_ERR_TRX_CANL_SHORT_TO_BAT: return "CANL short to BAT";
    case CAN_ERR_TRX_CANL_SHORT_TO_VCC: return "CANL short to VCC";
    case CAN_ERR_TRX_CANL_SHORT_TO_GND: return "CANL short to GND";
    case CAN_ERR_TRX_CANL_SHORT_TO_CANH: return "CANL short to CANH";
    default: return nullptr;
  }
}

}  // namespace

ErrorFrameInfo decode_error_frame(const can_frame& frame) {
  ErrorFrameInfo info;
  if (!is_error_frame(frame)) {
    info.description = "not an error frame";
    return info;
  }
  info.error_class = frame.can_id & CAN_ERR_MASK;
  // Error frames always carry CAN_ERR_DLC bytes; read missing bytes as 0 rather than trusting len.
  uint8_t d[CAN_ERR_DLC] = {};
  for (unsigned i = 0; i < CAN_ERR_DLC && i < frame.len && i < CAN_MAX_DLEN; ++i) d[i] = frame.data[i];

  std::vector<std::string> parts;
  const uint32_t c = info.error_class;
  if (c & CAN_ERR_TX_TIMEOUT) parts.emplace_back("TX timeout");
  if (c & CAN_ERR_LOSTARB) {
    parts.emplace_back(d[0] == CAN_ERR_LOSTARB_UNSPEC ? std::string("lost arbitration")
                                                      : "lost arbitration at bit " + std::to_string(d[0]));
  }
  if (c & CAN_ERR_CRTL) {
    info.overflow = d[1] & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW);
    info.error_warning = d[1] & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING);
    info.error_passive = d[1] & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE);
    info.back_to_error_active = d[1] & CAN_ERR_CRTL_ACTIVE;
    const std::string what = bit_names(d[1], {{CAN_ERR_CRTL_RX_OVERFLOW, "RX buffer overflow"},
                                              {CAN_ERR_CRTL_TX_OVERFLOW, "TX buffer overflow"},
                                              {CAN_ERR_CRTL_RX_WARNING, "RX error-warning"},
                                              {CAN_ERR_CRTL_TX_WARNING, "TX error-warning"},
                                              {CAN_ERR_CRTL_RX_PASSIVE, "RX error-passive"},
                                              {CAN_ERR_CRTL_TX_PASSIVE, "TX error-passive"},
                                              {CAN_ERR_CRTL_ACTIVE, "back to error-active"}});
    parts.push_back("controller: " + (what.empty() ? std::string("unspecified problem") : what));
  }
  if (c & CAN_ERR_PROT) {
    std::string what = bit_names(d[2], {{CAN_ERR_PROT_BIT, "bit error"},
                                        {CAN_ERR_PROT_FORM, "form error"},
                                        {CAN_ERR_PROT_STUFF, "stuff error"},
                                        {CAN_ERR_PROT_BIT0, "cannot send dominant bit"},
                                        {CAN_ERR_PROT_BIT1, "cannot send recessive bit"},
                                        {CAN_ERR_PROT_OVERLOAD, "bus overload"},
                                        {CAN_ERR_PROT_ACTIVE, "active error announcement"},
                                        {CAN_ERR_PROT_TX, "on transmission"}});
    if (what.empty()) what = "unspecified violation";
    if (const char* loc = protocol_location(d[3])) what += std::string(" at ") + loc;
    parts.push_back("protocol: " + what);
  }
  if (c & CAN_ERR_TRX) {
    const char* trx = transceiver_state(d[4]);
    parts.push_back(std::string("transceiver: ") + (trx ? trx : "unspecified problem"));
  }
  if (c & CAN_ERR_ACK) parts.emplace_back("no ACK on transmission");
  if (c & CAN_ERR_BUSOFF) {
    info.bus_off = true;
    parts.emplace_back("bus-off");
  }
  if (c & CAN_ERR_BUSERROR) parts.emplace_back("bus error");
  if (c & CAN_ERR_RESTARTED) {
    info.restarted = true;
    parts.emplace_back("controller restarted");
  }
  if (c & CAN_ERR_CNT) {
    info.has_error_counters = true;
    info.tx_error_count = d[6];
    info.rx_error_count = d[7];
    parts.push_back("TEC " + std::to_string(d[6]) + " REC " + std::to_string(d[7]));
  }
  if (parts.empty()) {
    char buf[48];
    std::snprintf(buf, sizeof buf, "error frame with unknown class 0x%X", c);
    parts.emplace_back(buf);
  }
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (i) info.description += "; ";
    info.description += parts[i];
  }
  return info;
}

}  // namespace nimble::can
