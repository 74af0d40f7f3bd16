#include "dcp/messages.hpp"

#include <algorithm>

namespace liftd::dcp {
namespace {

// Payload lengths including 'I' and the id character (DCP 5.12.2 to 5.12.9).
constexpr std::size_t kLenInitRequest = 16;  // I 0 HK1 HK2 V V V V D D M M Y Y LK1 LK2
constexpr std::size_t kLenInitReply = 17;    // ... plus the DCP type before LK1
constexpr std::size_t kInitTypeOffset = 14;  // 'I' '0' HK1 HK2 V V V V D D M M Y Y type
constexpr std::size_t kLenInitReplyMin = kInitTypeOffset + 1;  // the DCP type must be there
constexpr std::size_t kLenDataInfoRequest = 4;                 // I 1 protocol type
constexpr std::size_t kLenDataInfoBase = 2;                    // I 1
constexpr std::size_t kLenDataInfoExt = 3;                     // I 1 '1'
constexpr std::size_t kLenSwitch = 4;            // I 2 reserve function (both directions)
constexpr std::size_t kLenDateTimeRequest = 16;  // I 3 DDMMYYYYHHMMSS
constexpr std::size_t kLenBare = 2;              // I3 / I8 / base I9 replies
constexpr std::size_t kLenPower = 4;             // I 6 supply saving (both directions)
constexpr std::size_t kLenStartRequest = 8;      // I 7 Vmax Ss1..Ss5
constexpr std::size_t kLenStartReply = 13;       // I 7 ftyp Sg1..Sg5 Sv1..Sv5
constexpr std::size_t kLenLoadRequest = 5;       // I 8 L1 L2 L3
constexpr std::size_t kLenPosition = 9;          // I 9 SIGN P1..P6 (request and extended reply)

constexpr std::uint8_t kExtendedFlag = '1';      // DCP 5.12.3.2: "I11" = extended supported
constexpr std::int32_t kMaxSixDigits = 999999;   // DCP 5.12.9: six digits of mm
constexpr std::uint32_t kMaxFiveDigits = 99999;  // DCP 5.12.7: five digits of cm
constexpr std::uint16_t kMaxThreeDigits = 999;   // DCP 5.12.8: three digits of percent
constexpr std::uint16_t kMaxVersion = 9999;      // DCP 5.12.2: four version digits
constexpr std::uint16_t kMinI3Year = 2010;       // DCP 5.12.5.1: year 2010..9999
constexpr std::uint16_t kMaxI3Year = 9999;
constexpr unsigned kTwoDigitYearBase = 2000;  // DDMMYY software dates: 20YY for leap years

bool is_upper(std::uint8_t c) noexcept {
  return c >= 'A' && c <= 'Z';
}
bool is_digit(std::uint8_t c) noexcept {
  return c >= '0' && c <= '9';
}
bool valid_code(Code2 code) noexcept {
  return is_upper(static_cast<std::uint8_t>(code[0])) &&
         is_upper(static_cast<std::uint8_t>(code[1]));
}

bool leap(unsigned year) noexcept {
  return (year % 4 == 0 && year % 100 != 0) || year % 400 == 0;
}
unsigned days_in_month(unsigned month, unsigned year) noexcept {
  constexpr std::array<unsigned, 12> kDays = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  if (month < 1 || month > 12) return 0;
  return month == 2 && leap(year) ? 29 : kDays[month - 1];
}
bool valid_date(unsigned day, unsigned month, unsigned year) noexcept {
  return month >= 1 && month <= 12 && day >= 1 && day <= days_in_month(month, year);
}

// ---- writing --------------------------------------------------------------------------------

class Writer {
 public:
  explicit Writer(MessageId id) noexcept {
    put(kInternalCommand);
    put(static_cast<std::uint8_t>(id));
  }
  void put(std::uint8_t c) noexcept {
    if (out_.value.length < out_.value.data.size()) out_.value.data[out_.value.length++] = c;
  }
  void put(char c) noexcept { put(static_cast<std::uint8_t>(c)); }
  void put_code(Code2 code, MessageError error) noexcept {
    if (!valid_code(code)) fail(error);
    put(code[0]);
    put(code[1]);
  }
  // Writes `value` as `digits` decimal digits, most significant first.
  void put_digits(std::uint32_t value, std::size_t digits) noexcept {
    std::uint32_t limit = 1;
    for (std::size_t i = 0; i < digits; ++i) limit *= 10;
    if (value >= limit) fail(MessageError::ValueOutOfRange);
    for (std::size_t i = digits; i-- > 0;) {
      std::uint32_t divisor = 1;
      for (std::size_t k = 0; k < i; ++k) divisor *= 10;
      put(static_cast<std::uint8_t>('0' + (value / divisor) % 10));
    }
  }
  void put_signed(SignedMm value) noexcept {
    if (!value) {
      put('E');
      put_digits(0, 6);
      return;
    }
    if (*value < -kMaxSixDigits || *value > kMaxSixDigits) fail(MessageError::ValueOutOfRange);
    put(*value < 0 ? '-' : '+');
    put_digits(static_cast<std::uint32_t>(*value < 0 ? -*value : *value), 6);
  }
  void fail(MessageError error) noexcept {
    if (out_.ok()) out_.error = error;
  }
  Decoded<Payload> done() noexcept {
    if (!out_.ok()) out_.value = Payload{};
    return out_;
  }

 private:
  Decoded<Payload> out_{};
};

void put_date(Writer& w, SoftwareDate d) noexcept {
  if (d.year > 99 || !valid_date(d.day, d.month, kTwoDigitYearBase + d.year)) {
    w.fail(MessageError::BadDate);
  }
  w.put_digits(d.day, 2);
  w.put_digits(d.month, 2);
  w.put_digits(d.year, 2);
}

Decoded<Payload> encode_one(const InitRequest& m) noexcept {
  Writer w(MessageId::Init);
  w.put_code(m.maker, MessageError::BadMaker);
  w.put_digits(m.version, 4);
  put_date(w, m.date);
  w.put_code(m.language, MessageError::BadLanguage);
  return w.done();
}
Decoded<Payload> encode_one(const DataInfoRequest& m) noexcept {
  Writer w(MessageId::DataInfo);
  w.put(m.extended_protocol ? '1' : '0');
  if (!data_info_type_from_char(static_cast<char>(m.type))) w.fail(MessageError::BadDataInfoType);
  w.put(static_cast<std::uint8_t>(m.type));
  return w.done();
}
template <typename M>
Decoded<Payload> encode_switch(const M& m) noexcept {
  Writer w(MessageId::Switch);
  if (m.reserve < kFirstDataChar) w.fail(MessageError::NotDataChar);
  w.put(m.reserve);
  const auto f = static_cast<std::uint8_t>(m.function);
  if (f != '0' && f != '1' && f != 'R') w.fail(MessageError::BadSwitchFunction);
  w.put(f);
  return w.done();
}
Decoded<Payload> encode_one(const SwitchRequest& m) noexcept {
  return encode_switch(m);
}
Decoded<Payload> encode_one(const DateTimeRequest& m) noexcept {
  Writer w(MessageId::DateTime);
  const CivilTime& t = m.time;
  if (t.year < kMinI3Year || t.year > kMaxI3Year || !valid_date(t.day, t.month, t.year)) {
    w.fail(MessageError::BadDate);
  }
  if (t.hour > 23 || t.minute > 59 || t.second > 59) w.fail(MessageError::BadTime);
  w.put_digits(t.day, 2);
  w.put_digits(t.month, 2);
  w.put_digits(t.year, 4);
  w.put_digits(t.hour, 2);
  w.put_digits(t.minute, 2);
  w.put_digits(t.second, 2);
  return w.done();
}
template <typename M>
Decoded<Payload> encode_power(const M& m) noexcept {
  Writer w(MessageId::Power);
  const auto s = static_cast<std::uint8_t>(m.supply);
  if (s != 'N' && s != 'U') w.fail(MessageError::BadPowerSupply);
  const auto e = static_cast<std::uint8_t>(m.saving);
  if (e < '0' || e > '2') w.fail(MessageError::BadEnergySaving);
  w.put(s);
  w.put(e);
  return w.done();
}
Decoded<Payload> encode_one(const PowerRequest& m) noexcept {
  return encode_power(m);
}
Decoded<Payload> encode_one(const StartParamsRequest& m) noexcept {
  Writer w(MessageId::StartParams);
  const auto v = static_cast<std::uint8_t>(m.max_speed);
  if (v != '1' && v != '2') w.fail(MessageError::BadMaxSpeed);
  w.put(v);
  w.put_digits(m.distance_cm, 5);
  return w.done();
}
Decoded<Payload> encode_one(const LoadRequest& m) noexcept {
  Writer w(MessageId::Load);
  w.put_digits(m.load_percent, 3);
  return w.done();
}
Decoded<Payload> encode_one(const PositionRequest& m) noexcept {
  Writer w(MessageId::Position);
  w.put_signed(m.position_mm);
  return w.done();
}

Decoded<Payload> encode_one(const InitReply& m) noexcept {
  Writer w(MessageId::Init);
  w.put_code(m.maker, MessageError::BadMaker);
  w.put_digits(m.version, 4);
  put_date(w, m.date);
  switch (m.dcp_type) {
    case Protocol::ComChan:
      w.put('0');
      break;
    case Protocol::Dcp3:
      w.put('3');
      break;
    case Protocol::Dcp4:
      w.put('4');
      break;
    default:
      w.fail(MessageError::BadDcpType);
  }
  w.put_code(m.language, MessageError::BadLanguage);
  return w.done();
}
Decoded<Payload> encode_one(const DataInfoReply& m) noexcept {
  Writer w(MessageId::DataInfo);
  if (m.extended_protocol) w.put(kExtendedFlag);
  return w.done();
}
Decoded<Payload> encode_one(const SwitchReply& m) noexcept {
  return encode_switch(m);
}
Decoded<Payload> encode_one(const DateTimeReply&) noexcept {
  return Writer(MessageId::DateTime).done();
}
Decoded<Payload> encode_one(const PowerReply& m) noexcept {
  return encode_power(m);
}
Decoded<Payload> encode_one(const StartParamsReply& m) noexcept {
  Writer w(MessageId::StartParams);
  const auto k = static_cast<std::uint8_t>(m.kind);
  if (k != 's' && k != 'l') w.fail(MessageError::BadTravelKind);
  w.put(k);
  w.put_digits(m.total_cm, 5);
  w.put_digits(m.decel_cm, 5);
  return w.done();
}
Decoded<Payload> encode_one(const LoadReply&) noexcept {
  return Writer(MessageId::Load).done();
}
Decoded<Payload> encode_one(const PositionReply& m) noexcept {
  Writer w(MessageId::Position);
  if (m.extended) w.put_signed(m.travel_mm);
  return w.done();
}

// ---- reading --------------------------------------------------------------------------------

// Reads fields at increasing offsets; the first failure sticks.
class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> payload) noexcept : p_(payload) {}
  bool ok() const noexcept { return error_ == MessageError::None; }
  MessageError error() const noexcept { return error_; }
  std::size_t error_offset() const noexcept { return error_offset_; }
  void fail(MessageError error, std::size_t offset) noexcept {
    if (ok()) {
      error_ = error;
      error_offset_ = offset;
    }
  }
  std::uint8_t at(std::size_t i) const noexcept { return i < p_.size() ? p_[i] : 0; }
  // Reads `digits` decimal digits starting at `pos`.
  std::uint32_t digits(std::size_t pos, std::size_t digits) noexcept {
    std::uint32_t value = 0;
    for (std::size_t i = 0; i < digits; ++i) {
      const std::uint8_t c = at(pos + i);
      if (!is_digit(c)) {
        fail(MessageError::BadDigit, pos + i);
        return 0;
      }
      value = value * 10 + static_cast<std::uint32_t>(c - '0');
    }
    return value;
  }
  Code2 code(std::size_t pos, MessageError error) noexcept {
    const Code2 c{static_cast<char>(at(pos)), static_cast<char>(at(pos + 1))};
    if (!is_upper(at(pos))) fail(error, pos);
    if (!is_upper(at(pos + 1))) fail(error, pos + 1);
    return c;
  }
  SoftwareDate date(std::size_t pos) noexcept {
    SoftwareDate d;
    d.day = static_cast<std::uint8_t>(digits(pos, 2));
    d.month = static_cast<std::uint8_t>(digits(pos + 2, 2));
    d.year = static_cast<std::uint8_t>(digits(pos + 4, 2));
    if (ok() && !valid_date(d.day, d.month, kTwoDigitYearBase + d.year)) {
      fail(MessageError::BadDate, pos);
    }
    return d;
  }
  SignedMm signed_mm(std::size_t pos) noexcept {
    const std::uint8_t sign = at(pos);
    if (sign != '+' && sign != '-' && sign != 'E') fail(MessageError::BadSign, pos);
    const auto magnitude = static_cast<std::int32_t>(digits(pos + 1, 6));
    if (sign == 'E') return std::nullopt;
    return sign == '-' ? -magnitude : magnitude;
  }
  template <typename T>
  Decoded<T> result(T value) const noexcept {
    Decoded<T> out;
    if (ok()) {
      out.value = std::move(value);
    } else {
      out.error = error_;
      out.offset = error_offset_;
    }
    return out;
  }

 private:
  std::span<const std::uint8_t> p_;
  MessageError error_ = MessageError::None;
  std::size_t error_offset_ = 0;
};

template <typename T>
Decoded<T> failed(MessageError error, std::size_t offset) noexcept {
  Decoded<T> out;
  out.error = error;
  out.offset = offset;
  return out;
}

bool known_id(std::uint8_t c) noexcept {
  return c == '0' || c == '1' || c == '2' || c == '3' || c == '6' || c == '7' || c == '8' ||
         c == '9';
}

// Common head checks: 'I', a known id, data characters only. Returns the id or an error.
template <typename T>
std::optional<Decoded<T>> check_head(std::span<const std::uint8_t> p, MessageId& id) noexcept {
  if (p.empty()) return failed<T>(MessageError::Empty, 0);
  if (p[0] != kInternalCommand) return failed<T>(MessageError::NotInternal, 0);
  if (p.size() < 2) return failed<T>(MessageError::WrongLength, 0);
  if (!known_id(p[1])) return failed<T>(MessageError::UnknownId, 1);
  for (std::size_t i = 2; i < p.size(); ++i) {
    if (!is_data_char(p[i])) return failed<T>(MessageError::NotDataChar, i);
  }
  id = static_cast<MessageId>(p[1]);
  return std::nullopt;
}

template <typename Variant, typename T>
Decoded<Variant> widen(Decoded<T> d) noexcept {
  Decoded<Variant> out;
  out.error = d.error;
  out.offset = d.offset;
  if (d.ok()) out.value = std::move(d.value);
  return out;
}

Decoded<CivilTime> read_civil(Reader& r, std::size_t pos) noexcept {
  CivilTime t;
  t.day = static_cast<std::uint8_t>(r.digits(pos, 2));
  t.month = static_cast<std::uint8_t>(r.digits(pos + 2, 2));
  t.year = static_cast<std::uint16_t>(r.digits(pos + 4, 4));
  t.hour = static_cast<std::uint8_t>(r.digits(pos + 8, 2));
  t.minute = static_cast<std::uint8_t>(r.digits(pos + 10, 2));
  t.second = static_cast<std::uint8_t>(r.digits(pos + 12, 2));
  if (r.ok() && (t.year < kMinI3Year || !valid_date(t.day, t.month, t.year))) {
    r.fail(MessageError::BadDate, pos);
  }
  if (r.ok() && (t.hour > 23 || t.minute > 59 || t.second > 59)) {
    r.fail(MessageError::BadTime, pos + 8);
  }
  return r.result(t);
}

template <typename M>
Decoded<M> read_switch(Reader& r) noexcept {
  M m;
  m.reserve = r.at(2);
  const std::uint8_t f = r.at(3);
  if (f != '0' && f != '1' && f != 'R') r.fail(MessageError::BadSwitchFunction, 3);
  m.function = static_cast<SwitchFunction>(f);
  return r.result(m);
}

template <typename M>
Decoded<M> read_power(Reader& r) noexcept {
  M m;
  const std::uint8_t s = r.at(2);
  if (s != 'N' && s != 'U') r.fail(MessageError::BadPowerSupply, 2);
  const std::uint8_t e = r.at(3);
  if (e < '0' || e > '2') r.fail(MessageError::BadEnergySaving, 3);
  m.supply = static_cast<PowerSupply>(s);
  m.saving = static_cast<EnergySaving>(e);
  return r.result(m);
}

}  // namespace

std::string_view to_string(MessageId id) noexcept {
  switch (id) {
    case MessageId::Init:
      return "I0";
    case MessageId::DataInfo:
      return "I1";
    case MessageId::Switch:
      return "I2";
    case MessageId::DateTime:
      return "I3";
    case MessageId::Power:
      return "I6";
    case MessageId::StartParams:
      return "I7";
    case MessageId::Load:
      return "I8";
    case MessageId::Position:
      return "I9";
  }
  return "I?";
}

std::string_view to_string(MessageError error) noexcept {
  switch (error) {
    case MessageError::None:
      return "no error";
    case MessageError::Empty:
      return "empty payload";
    case MessageError::NotInternal:
      return "first character is not 'I' (0x49)";
    case MessageError::UnknownId:
      return "unknown I-message number";
    case MessageError::WrongLength:
      return "wrong length for this message";
    case MessageError::NotDataChar:
      return "control character inside the message";
    case MessageError::BadDigit:
      return "a character that must be a digit is not one";
    case MessageError::BadMaker:
      return "maker code is not two upper-case letters";
    case MessageError::BadLanguage:
      return "language code is not two upper-case letters";
    case MessageError::BadDate:
      return "not a valid date";
    case MessageError::BadTime:
      return "not a valid time of day";
    case MessageError::BadDcpType:
      return "DCP type is not '0', '3' or '4'";
    case MessageError::BadProtocolType:
      return "protocol type is not '0' or '1'";
    case MessageError::BadDataInfoType:
      return "data-information-type is not '0'..'4'";
    case MessageError::BadSwitchFunction:
      return "switching function is not '0', '1' or 'R'";
    case MessageError::BadPowerSupply:
      return "power supply is not 'N' or 'U'";
    case MessageError::BadEnergySaving:
      return "energy saving mode is not '0', '1' or '2'";
    case MessageError::BadMaxSpeed:
      return "maximum speed is not '1' or '2'";
    case MessageError::BadTravelKind:
      return "travel type is not 's' or 'l'";
    case MessageError::BadSign:
      return "sign is not '+', '-' or 'E'";
    case MessageError::ValueOutOfRange:
      return "value does not fit its digits";
    case MessageError::BadButtons:
      return "keypad byte has bits other than 0x04..0x40";
  }
  return "unknown message error";
}

bool valid_civil_time(const CivilTime& t) noexcept {
  return t.year >= kMinI3Year && t.year <= kMaxI3Year && valid_date(t.day, t.month, t.year) &&
         t.hour <= 23 && t.minute <= 59 && t.second <= 59;
}

MessageId message_id(const MasterMessage& message) noexcept {
  constexpr std::array<MessageId, 8> kIds = {
      MessageId::Init,  MessageId::DataInfo,    MessageId::Switch, MessageId::DateTime,
      MessageId::Power, MessageId::StartParams, MessageId::Load,   MessageId::Position};
  return kIds[message.index()];
}
MessageId message_id(const DriveMessage& message) noexcept {
  constexpr std::array<MessageId, 8> kIds = {
      MessageId::Init,  MessageId::DataInfo,    MessageId::Switch, MessageId::DateTime,
      MessageId::Power, MessageId::StartParams, MessageId::Load,   MessageId::Position};
  return kIds[message.index()];
}

Decoded<Payload> encode(const MasterMessage& message) noexcept {
  return std::visit([](const auto& m) { return encode_one(m); }, message);
}
Decoded<Payload> encode(const DriveMessage& message) noexcept {
  return std::visit([](const auto& m) { return encode_one(m); }, message);
}

Decoded<MasterMessage> decode_master_message(std::span<const std::uint8_t> p) noexcept {
  MessageId id{};
  if (auto head = check_head<MasterMessage>(p, id)) return *head;
  Reader r(p);
  auto length_is = [&](std::size_t n) {
    if (p.size() != n) r.fail(MessageError::WrongLength, 0);
    return r.ok();
  };
  switch (id) {
    case MessageId::Init: {
      if (!length_is(kLenInitRequest)) break;
      InitRequest m;
      m.maker = r.code(2, MessageError::BadMaker);
      m.version = static_cast<VersionCenti>(r.digits(4, 4));
      m.date = r.date(8);
      m.language = r.code(14, MessageError::BadLanguage);
      return widen<MasterMessage>(r.result(m));
    }
    case MessageId::DataInfo: {
      if (!length_is(kLenDataInfoRequest)) break;
      DataInfoRequest m;
      if (p[2] != '0' && p[2] != '1') r.fail(MessageError::BadProtocolType, 2);
      m.extended_protocol = p[2] == '1';
      const auto type = data_info_type_from_char(static_cast<char>(p[3]));
      if (!type) r.fail(MessageError::BadDataInfoType, 3);
      m.type = type.value_or(DataInfoType::Alternating);
      return widen<MasterMessage>(r.result(m));
    }
    case MessageId::Switch:
      if (!length_is(kLenSwitch)) break;
      return widen<MasterMessage>(read_switch<SwitchRequest>(r));
    case MessageId::DateTime: {
      if (!length_is(kLenDateTimeRequest)) break;
      const auto t = read_civil(r, 2);
      return widen<MasterMessage>(r.result(DateTimeRequest{t.value}));
    }
    case MessageId::Power:
      if (!length_is(kLenPower)) break;
      return widen<MasterMessage>(read_power<PowerRequest>(r));
    case MessageId::StartParams: {
      if (!length_is(kLenStartRequest)) break;
      StartParamsRequest m;
      if (p[2] != '1' && p[2] != '2') r.fail(MessageError::BadMaxSpeed, 2);
      m.max_speed = static_cast<MaxSpeed>(p[2]);
      m.distance_cm = r.digits(3, 5);
      return widen<MasterMessage>(r.result(m));
    }
    case MessageId::Load: {
      if (!length_is(kLenLoadRequest)) break;
      LoadRequest m;
      m.load_percent = static_cast<std::uint16_t>(r.digits(2, 3));
      return widen<MasterMessage>(r.result(m));
    }
    case MessageId::Position: {
      if (!length_is(kLenPosition)) break;
      PositionRequest m;
      m.position_mm = r.signed_mm(2);
      return widen<MasterMessage>(r.result(m));
    }
  }
  return failed<MasterMessage>(r.error(), r.error_offset());
}

Decoded<DriveMessage> decode_drive_message(std::span<const std::uint8_t> p) noexcept {
  MessageId id{};
  if (auto head = check_head<DriveMessage>(p, id)) return *head;
  Reader r(p);
  auto length_is = [&](std::size_t n) {
    if (p.size() != n) r.fail(MessageError::WrongLength, 0);
    return r.ok();
  };
  switch (id) {
    case MessageId::Init: {
      // Tolerant on purpose: older and other drives fill maker, version, date and language in
      // their own ways; only the DCP type character (DCP 5.12.2.2, after the date) decides.
      if (p.size() < kLenInitReplyMin) {
        r.fail(MessageError::WrongLength, 0);
        break;
      }
      InitReply m;
      if (p.size() != kLenInitReply) m.anomalies |= init_anomaly::kLength;
      switch (p[kInitTypeOffset]) {
        case '0':
          m.dcp_type = Protocol::ComChan;
          break;
        case '3':
          m.dcp_type = Protocol::Dcp3;
          break;
        case '4':
          m.dcp_type = Protocol::Dcp4;
          break;
        default:
          r.fail(MessageError::BadDcpType, kInitTypeOffset);
      }
      if (!r.ok()) break;
      Reader lenient(p);
      m.maker = lenient.code(2, MessageError::BadMaker);
      if (!lenient.ok()) m.anomalies |= init_anomaly::kMaker;
      Reader version(p);
      m.version = static_cast<VersionCenti>(version.digits(4, 4));
      if (!version.ok()) m.anomalies |= init_anomaly::kVersion;
      Reader date(p);
      m.date = date.date(8);
      if (!date.ok()) {
        m.anomalies |= init_anomaly::kDate;
        m.date = SoftwareDate{};
      }
      Reader language(p);
      if (p.size() >= kLenInitReply) m.language = language.code(15, MessageError::BadLanguage);
      if (p.size() < kLenInitReply || !language.ok()) {
        m.anomalies |= init_anomaly::kLanguage;
        m.language = Code2{'E', 'N'};
      }
      return widen<DriveMessage>(r.result(m));
    }
    case MessageId::DataInfo: {
      DataInfoReply m;
      if (p.size() == kLenDataInfoExt) {
        if (p[2] != kExtendedFlag) r.fail(MessageError::BadProtocolType, 2);
        m.extended_protocol = true;
      } else if (!length_is(kLenDataInfoBase)) {
        break;
      }
      return widen<DriveMessage>(r.result(m));
    }
    case MessageId::Switch:
      if (!length_is(kLenSwitch)) break;
      return widen<DriveMessage>(read_switch<SwitchReply>(r));
    case MessageId::DateTime:
      if (!length_is(kLenBare)) break;
      return widen<DriveMessage>(r.result(DateTimeReply{}));
    case MessageId::Power:
      if (!length_is(kLenPower)) break;
      return widen<DriveMessage>(read_power<PowerReply>(r));
    case MessageId::StartParams: {
      if (!length_is(kLenStartReply)) break;
      StartParamsReply m;
      if (p[2] != 's' && p[2] != 'l') r.fail(MessageError::BadTravelKind, 2);
      m.kind = static_cast<TravelKind>(p[2]);
      m.total_cm = r.digits(3, 5);
      m.decel_cm = r.digits(8, 5);
      return widen<DriveMessage>(r.result(m));
    }
    case MessageId::Load:
      if (!length_is(kLenBare)) break;
      return widen<DriveMessage>(r.result(LoadReply{}));
    case MessageId::Position: {
      PositionReply m;
      if (p.size() == kLenPosition) {
        m.extended = true;
        m.travel_mm = r.signed_mm(2);
      } else if (!length_is(kLenBare)) {
        break;
      }
      return widen<DriveMessage>(r.result(m));
    }
  }
  return failed<DriveMessage>(r.error(), r.error_offset());
}

namespace {
struct MakerName {
  std::array<char, 2> code;
  std::string_view name;
};
// DCP 5.12.2.3, drive controller makers.
constexpr std::array<MakerName, 15> kDriveMakers = {{
    {{'A', 'B'}, "ABB"},
    {{'B', 'F'}, "Brunner & Fecher Regelungstechnik GbR"},
    {{'B', 'H'}, "Bucher Hydraulics AG"},
    {{'C', 'T'}, "Control Techniques GmbH"},
    {{'D', 'A'}, "Danfoss GmbH"},
    {{'D', 'E'}, "Emotron Lift Center GmbH"},
    {{'F', 'E'}, "Fuji Electric GmbH"},
    {{'S', 'S'}, "Gefran Deutschland GmbH"},
    {{'K', 'W'}, "KW-Aufzugstechnik GmbH"},
    {{'M', 'T'}, "MagneTek (UK) Ltd."},
    {{'R', 'S'}, "RST Elektronik GmbH"},
    {{'T', 'Y'}, "Thyssen Krupp Aufzugswerke GmbH"},
    {{'V', 'Z'}, "Venzke-DriveCon GmbH"},
    {{'Y', 'E'}, "Yaskawa Europe GmbH"},
    {{'Z', 'A'}, "Ziehl-Abegg AG"},
}};
// DCP 5.12.2.3, lift controller makers.
constexpr std::array<MakerName, 6> kControllerMakers = {{
    {{'B', 'P'}, "Boehnke + Partner GmbH"},
    {{'K', 'N'}, "Kollmorgen Steuerungstechnik GmbH"},
    {{'N', 'L'}, "NEW LIFT Steuerungsbau GmbH"},
    {{'O', 'S'}, "OSMA-Aufzuege, Albert Schenk GmbH & Co KG"},
    {{'L', 'I'}, "Schneider Steuerungstechnik GmbH"},
    {{'S', 'T'}, "Strack Lift Automation GmbH"},
}};
template <std::size_t N>
std::string_view find_maker(const std::array<MakerName, N>& table, Code2 code) noexcept {
  for (const auto& m : table) {
    if (m.code == code) return m.name;
  }
  return {};
}
}  // namespace

std::string_view drive_maker_name(Code2 code) noexcept {
  return find_maker(kDriveMakers, code);
}
std::string_view controller_maker_name(Code2 code) noexcept {
  return find_maker(kControllerMakers, code);
}

Decoded<Payload> encode_keypad(std::uint8_t buttons) noexcept {
  Decoded<Payload> out;
  if (!valid_keypad_buttons(buttons)) {
    out.error = MessageError::BadButtons;
    return out;
  }
  out.value.data[0] = buttons;
  out.value.length = 1;
  return out;
}

Decoded<std::uint8_t> decode_keypad(std::span<const std::uint8_t> payload) noexcept {
  if (payload.empty()) return failed<std::uint8_t>(MessageError::Empty, 0);
  if (payload.size() != 1) return failed<std::uint8_t>(MessageError::WrongLength, 0);
  if (!valid_keypad_buttons(payload[0])) return failed<std::uint8_t>(MessageError::BadButtons, 0);
  Decoded<std::uint8_t> out;
  out.value = payload[0];
  return out;
}

Decoded<DriveErrorText> decode_drive_error(std::span<const std::uint8_t> payload) noexcept {
  if (payload.empty()) return failed<DriveErrorText>(MessageError::Empty, 0);
  if (payload.size() > kMaxChannelPayload) {
    return failed<DriveErrorText>(MessageError::WrongLength, 0);
  }
  for (std::size_t i = 0; i < payload.size(); ++i) {
    if (!is_data_char(payload[i])) return failed<DriveErrorText>(MessageError::NotDataChar, i);
  }
  Decoded<DriveErrorText> out;
  std::copy(payload.begin(), payload.end(), out.value.data.begin());
  out.value.length = payload.size();
  return out;
}

}  // namespace liftd::dcp
