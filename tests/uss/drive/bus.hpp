// The USS controller driven as the runner drives it, without a serial port: a real uss::Master
// builds every telegram, the fake drive (fake_drive.hpp) takes STW/HSW from those bytes and
// answers with a reply telegram encoded by the codec (encode_payload / encode_telegram), fed to
// the master character by character with the character times of 38400 baud; then
// after_exchange(). The STW each telegram carried is read back from the bytes on the wire.
// Used by controller_test.cpp and alloc_test.cpp.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <optional>
#include <vector>

#include "uss/drive/controller.hpp"
#include "uss/drive/fake_drive.hpp"
#include "uss/telegram.hpp"
#include "uss/timing.hpp"

namespace liftd::uss::test {

using std::chrono::milliseconds;

inline constexpr std::uint8_t kDrive = 1;
inline constexpr std::uint32_t kBaud = 38400;
inline constexpr std::uint16_t kParameter = 52;  ///< the fake drive's one readable parameter
inline constexpr std::uint16_t kParameterValue = 1234;

class CarPosition final : public PositionSource {
 public:
  explicit CarPosition(const Car& car) : car_(car) {}
  std::optional<std::int64_t> position_mm(MonoTime) const noexcept override {
    if (!valid) return std::nullopt;
    return std::llround(car_.position_mm);
  }
  bool valid = true;

 private:
  const Car& car_;
};

inline MasterConfig master_config() {
  MasterConfig m;
  m.baud = kBaud;
  SlaveConfig drive;
  drive.address = kDrive;
  drive.pkw = PkwLength::Four;
  drive.pzd_words = 2;
  m.slaves = {drive};
  m.polling_list = {kDrive};
  m.mirror_at_start = false;
  return m;
}

inline UssControllerConfig controller_config() {
  UssControllerConfig c;
  c.drive_address = kDrive;
  c.floors_mm = {0, 3000, 6000, 9000};
  c.travel.slowdown_mm[speed_index(SpeedName::V4)] = 700;
  c.travel.slowdown_mm[speed_index(SpeedName::V3)] = 400;
  c.travel.stop_lead_mm = 2;
  c.link_fault_replies = 3;
  return c;
}

class Bus {
 public:
  explicit Bus(const UssControllerConfig& config = controller_config())
      : master(master_config()), position(car), controller(config, master, position, now) {
    inputs.valid = inputs.safety_chain_closed = true;
    inputs.doors_closed = inputs.doors_locked = true;
    controller.on_port(true, now);
    for (int i = 0; i < 10; ++i) exchange();
    drain();
  }

  /// One exchange as the runner does it, then after_exchange().
  void exchange() {
    ControllerCommand inputs_command;
    inputs_command.body = InputsCommand{inputs};
    EXPECT_TRUE(controller.post(inputs_command));
    const MonoTime before = now;
    now = std::max(now, master.send_at());
    const auto bytes = master.next_telegram(now);
    ASSERT_GE(bytes.size(), 4U);
    const std::vector<std::uint8_t> request(bytes.begin(), bytes.end());
    const MonoTime sent_end = now + transmission_time(kBaud, request.size());
    master.on_sent(sent_end);
    const AddressByte adr = parse_adr(request[2]);
    std::vector<std::uint8_t> reply;
    if (adr.type == TelegramType::Mirror) {
      reply = request;  // A 5.3: sent back "ohne irgendwelche Veränderungen"
    } else {
      ASSERT_EQ(adr.type, TelegramType::Normal);
      Pkw pkw;
      std::array<std::uint16_t, 2> pzd{};
      ASSERT_TRUE(decode_payload(std::span(request).subspan(3, request.size() - 4), PkwLength::Four,
                                 2, pkw, pzd));
      stw_sent.push_back(pzd[0]);
      hsw_sent.push_back(static_cast<std::int16_t>(pzd[1]));
      drive.receive(pzd[0], norm.from_raw(static_cast<std::int16_t>(pzd[1])), sent_end - last_);
      last_ = sent_end;
      // C 4.2.1.1: read parameter value (AK 1) -> transfer value (AK 1), else no reply (AK 0).
      Pkw answer;
      answer.toggle = pkw.toggle;
      if (pkw.id == 1 && pkw.pnu == kParameter) {
        answer.id = 1;
        answer.pnu = kParameter;
        set_value(answer, PkwLength::Four, PkwWidth::Word, kParameterValue);
      }
      const std::array<std::uint16_t, 2> zsw_hiw = {
          drive.zsw(), static_cast<std::uint16_t>(norm.to_raw(drive.actual()))};
      std::array<std::uint8_t, kMaxPayloadBytes> payload{};
      const std::size_t n = encode_payload(answer, PkwLength::Four, zsw_hiw, payload);
      ASSERT_GT(n, 0U);
      reply.resize(telegram_bytes(n));
      ASSERT_EQ(encode_telegram(make_adr(kDrive, TelegramType::Normal), std::span(payload).first(n),
                                reply),
                reply.size());
    }
    if (drive_answers) {
      // Characters stamped when complete, the STX 1 ms after our BCC (reply delay, A 5.2.1.1).
      MonoTime t = sent_end + milliseconds(1);
      for (std::uint8_t b : reply) {
        t += character_time(kBaud);
        master.on_char(RxChar{b, LineError::None}, t);
      }
      now = t;
    } else {
      now = master.deadline();
      master.on_time(now);
    }
    ASSERT_FALSE(master.awaiting_reply());
    car.advance(drive.actual(), controller.travel().output().brake_open, now - before);
    if (around_step) around_step(true);
    controller.after_exchange(now);
    if (around_step) around_step(false);
    drain();
  }

  bool run_until(const std::function<bool()>& done, int limit_ms = 60000) {
    const MonoTime end = now + milliseconds(limit_ms);
    while (now < end) {
      exchange();
      if (done()) return true;
    }
    return false;
  }

  void post(std::uint32_t tag, CommandBody body) {
    ControllerCommand c;
    c.tag = tag;
    c.body = body;
    ASSERT_TRUE(controller.post(c));
  }
  /// Posts, runs one exchange and returns the reply to `tag`.
  CommandReply command(std::uint32_t tag, CommandBody body) {
    post(tag, body);
    exchange();
    for (const CommandReply& r : replies) {
      if (r.tag == tag) return r;
    }
    ADD_FAILURE() << "no reply to " << tag;
    return {};
  }

  void drain() {
    CommandReply r;
    while (controller.poll_reply(r)) {
      if (r.tag != 0) replies.push_back(r);
    }
    ControllerEvent e;
    while (controller.poll_event(e)) events.push_back(e);
  }
  std::vector<ControllerEvent> travel_events() const {
    std::vector<ControllerEvent> out;
    for (const auto& e : events) {
      if (e.kind == ControllerEvent::Kind::Travel) out.push_back(e);
    }
    return out;
  }
  int count(ControllerEvent::Kind kind, FaultCode fault) const {
    int n = 0;
    for (const auto& e : events) n += e.kind == kind && e.fault == fault ? 1 : 0;
    return n;
  }
  bool idle() { return !controller.travel().busy(); }

  MonoTime now{std::chrono::seconds(1)};
  Normalisation norm;
  Master master;
  FakeDrive drive;
  Car car;
  CarPosition position;
  UssController controller;
  lift::Inputs inputs;
  bool drive_answers = true;
  /// Called with true just before and false just after the controller's step (the work of the
  /// real-time thread), e.g. to count allocations there only.
  std::function<void(bool)> around_step;
  std::vector<std::uint16_t> stw_sent;
  std::vector<std::int16_t> hsw_sent;
  std::vector<CommandReply> replies;
  std::vector<ControllerEvent> events;

 private:
  MonoTime last_{std::chrono::seconds(1)};
};

}  // namespace liftd::uss::test
