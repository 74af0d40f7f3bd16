// The simulated DCP drive's communication channel (DCP 5): received messages, I-messages,
// error messages, the keypad and the remote display.
#include "dcp/sim/drive_sim.hpp"

#include <algorithm>
#include <cstdio>
#include <string_view>

#include "dcp/sim/drive_sim_detail.hpp"

namespace liftd::dcp::sim {

using namespace detail;

// ---------------------------------------------------------------- channel (DCP 5)

void DriveSim::process_channel(std::uint8_t byte, MonoTime now) noexcept {
  switch (parser_.feed(byte, now)) {
    case dcp::ParseStatus::Reset:
      if (parser_.reset_reason() == dcp::ChannelReset::StxEtx) {
        // DCP 5.10: STX ETX returns both ends to their initial state (display cleared).
        out_.clear();
        display_active_ = false;
        emit(SimEvent::Kind::ChannelReset, now, 1);
      }
      break;
    case dcp::ParseStatus::Complete: {
      const dcp::ChannelFrame& frame = parser_.frame();
      if (frame.mode == dcp::ChannelMode::Expanded) {
        handle_i_message(frame.payload(), now);
      } else if (frame.mode == dcp::ChannelMode::Remote) {
        const auto keys = dcp::decode_keypad(frame.payload());
        if (keys.ok()) handle_keypad(keys.value, now);
      }
      break;
    }
    case dcp::ParseStatus::NeedMore:
    case dcp::ParseStatus::Bad:
      break;
  }
}

void DriveSim::send_error_message(std::string_view text) noexcept {
  std::array<std::uint8_t, 20> body{};  // DCP 5.11: 1..20 characters
  const std::size_t n = std::min(text.size(), body.size());
  for (std::size_t i = 0; i < n; ++i) body[i] = static_cast<std::uint8_t>(text[i]);
  out_.push_message(dcp::channel_char::kModeDriveError,
                    std::span<const std::uint8_t>(body.data(), n));
}

void DriveSim::handle_i_message(std::span<const std::uint8_t> payload, MonoTime now) noexcept {
  const auto request = dcp::decode_master_message(payload);
  if (!request.ok()) {
    if (payload.size() >= 2 && payload[1] == static_cast<std::uint8_t>(dcp::MessageId::Init)) {
      // DCP 5.12.2: no travel after a faulty I0; report it.
      initialised_ = false;
      send_error_message("INIT MESSAGE INVALID");
    }
    return;  // anything else unreadable: no answer
  }
  std::optional<dcp::DriveMessage> reply;
  std::visit(
      [&](const auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, dcp::InitRequest>) {
          // DCP 5.12.2: switch to the master's language, English when not supported.
          const bool german = m.language == dcp::Code2{'D', 'E'};
          language_ = german ? dcp::Code2{'D', 'E'} : dcp::Code2{'E', 'N'};
          initialised_ = true;
          data_info_type_ = dcp::DataInfoType::Alternating;  // DCP 5.12.3: '0' until I1
          extended_i9_ = false;
          reply = dcp::InitReply{config_.maker, config_.version, config_.date, config_.protocol,
                                 language_};
        } else if constexpr (std::is_same_v<T, dcp::DataInfoRequest>) {
          // An older drive knows no I1 and stays at type '0' (DCP 5.12.3.1).
          if (config_.older_drive) return;
          data_info_type_ = m.type;
          extended_i9_ = m.extended_protocol;  // DCP 5.12.3.2: extended protocol supported
          reply = dcp::DataInfoReply{m.extended_protocol};
        } else if constexpr (std::is_same_v<T, dcp::SwitchRequest>) {
          dcp::SwitchReply r{dcp::SwitchFunction::None, m.reserve};
          switch (m.function) {
            case dcp::SwitchFunction::None:
              reset_pending_ = false;  // DCP 5.12.4: cancel inside the 200 ms window
              max_torque_ = false;
              break;
            case dcp::SwitchFunction::MaxTorque:
              max_torque_ = true;
              r.function = dcp::SwitchFunction::MaxTorque;
              break;
            case dcp::SwitchFunction::Reset:
              // DCP 5.12.4.2: answer '0' when the fault cannot be reset.
              if (!faults_[cause_index(FaultCause::Injected)]) {
                reset_pending_ = true;
                // DCP 5.12.4: at least 200 ms after the reply, at most 1000 ms.
                reset_at_ = now + std::chrono::milliseconds(config_.reset_delay_ms);
                r.function = dcp::SwitchFunction::Reset;
              }
              break;
          }
          reply = r;
        } else if constexpr (std::is_same_v<T, dcp::DateTimeRequest>) {
          date_time_ = m.time;
          reply = dcp::DateTimeReply{};
        } else if constexpr (std::is_same_v<T, dcp::PowerRequest>) {
          power_supply_ = m.supply;  // both supplies and all saving modes are supported
          energy_mode_ = m.saving;
          reply = dcp::PowerReply{power_supply_, energy_mode_};
        } else if constexpr (std::is_same_v<T, dcp::StartParamsRequest>) {
          const StartParameters p =
              start_parameters(m.distance_cm, m.max_speed == dcp::MaxSpeed::V4);
          i7_decel_m_ = static_cast<double>(p.decel_cm) / 100.0;
          reply = dcp::StartParamsReply{
              p.travel_type == 'l' ? dcp::TravelKind::Long : dcp::TravelKind::Short, p.total_cm,
              p.decel_cm};
        } else if constexpr (std::is_same_v<T, dcp::LoadRequest>) {
          load_percent_ = m.load_percent;
          reply = dcp::LoadReply{};
        } else if constexpr (std::is_same_v<T, dcp::PositionRequest>) {
          if (m.position_mm) controller_position_mm_ = *m.position_mm;
          stop_without_i9_ = false;
          // DCP 5.12.9.2: extended reply with the distance measured over the last travel.
          dcp::SignedMm travel;
          if (travel_measured_) travel = static_cast<std::int32_t>(last_travel_mm_);
          reply = dcp::PositionReply{extended_i9_, travel};
        }
      },
      request.value);
  if (!reply) return;
  const auto encoded = dcp::encode(*reply);
  if (!encoded.ok()) return;
  ++counters_.i_messages;
  emit(SimEvent::Kind::ChannelMessage, now, payload[1]);
  if (config_.older_drive && std::holds_alternative<dcp::InitReply>(*reply)) {
    // An older drive's I0 reply: version "1.00" and date "000000" (no digits / no date), the
    // DCP type character still in its place (DCP 5.12.2.2).
    std::array<std::uint8_t, 32> body{};
    const auto bytes = encoded.value.bytes();
    const std::size_t n = std::min(bytes.size(), body.size());
    std::copy_n(bytes.begin(), n, body.begin());
    constexpr std::array<std::uint8_t, 10> kOdd{'1', '.', '0', '0', '0', '0', '0', '0', '0', '0'};
    std::copy(kOdd.begin(), kOdd.end(), body.begin() + 4);  // after 'I' '0' HK1 HK2
    out_.push_message(dcp::channel_char::kModeExpanded,
                      std::span<const std::uint8_t>(body.data(), n));
    return;
  }
  out_.push_message(dcp::channel_char::kModeExpanded, encoded.value.bytes());
}

void DriveSim::handle_keypad(std::uint8_t buttons, MonoTime now) noexcept {
  constexpr int kPages = 4;
  const bool first = !display_active_;
  display_active_ = true;
  const int before = menu_page_;
  // DCP 5.6.3: button "1" = previous page, button "2" = next page.
  if ((buttons & 0x04) != 0) menu_page_ = (menu_page_ + kPages - 1) % kPages;
  if ((buttons & 0x08) != 0) menu_page_ = (menu_page_ + 1) % kPages;
  display_refresh_ = now;
  render_display();
  flush_display(first || before != menu_page_);
}

void DriveSim::render_display() noexcept {
  std::array<char, 21> line{};
  auto set = [&](int row) {
    auto& dst = display_[static_cast<std::size_t>(row)];
    dst.fill(' ');
    for (std::size_t i = 0; i < dst.size() && line[i] != '\0'; ++i) dst[i] = line[i];
  };
  const bool de = language_[0] == 'D';
  switch (menu_page_) {
    case 0:
      std::snprintf(line.data(), line.size(), "DCP%c SIM %s",
                    config_.protocol == dcp::Protocol::Dcp3 ? '3' : '4', de ? "STATUS" : "STATUS");
      set(0);
      std::snprintf(line.data(), line.size(), "%s %+08.0f mm", de ? "Pos" : "Pos", position_mm());
      set(1);
      std::snprintf(line.data(), line.size(), "v %+6.3f m/s", velocity_mps());
      set(2);
      std::snprintf(line.data(), line.size(), "%.*s", 20, to_string(phase_).data());
      set(3);
      break;
    case 1:
      std::snprintf(line.data(), line.size(), "%s", de ? "FAHRTEN" : "TRAVELS");
      set(0);
      std::snprintf(line.data(), line.size(), "%.*s", 20, to_string(kind_).data());
      set(1);
      std::snprintf(line.data(), line.size(), "%s %+lld mm", de ? "zuletzt" : "last",
                    static_cast<long long>(last_travel_mm_));
      set(2);
      std::snprintf(line.data(), line.size(), "%s %llu", de ? "Anzahl" : "count",
                    static_cast<unsigned long long>(counters_.travels));
      set(3);
      break;
    case 2:
      std::snprintf(line.data(), line.size(), "DCP LINK");
      set(0);
      std::snprintf(line.data(), line.size(), "frames %llu",
                    static_cast<unsigned long long>(counters_.frames));
      set(1);
      std::snprintf(line.data(), line.size(), "bad %llu",
                    static_cast<unsigned long long>(counters_.bad_frames));
      set(2);
      std::snprintf(line.data(), line.size(), "repeats %llu",
                    static_cast<unsigned long long>(counters_.repeats));
      set(3);
      break;
    default: {
      std::snprintf(line.data(), line.size(), "%s", de ? "FEHLER" : "FAULTS");
      set(0);
      for (int row = 1; row < 4; ++row) {
        const auto cause = static_cast<FaultCause>(row - 1);
        std::snprintf(line.data(), line.size(), "%c %.*s", faults_[cause_index(cause)] ? '*' : '-',
                      18, to_string(cause).data());
        set(row);
      }
      break;
    }
  }
}

void DriveSim::flush_display(bool all) noexcept {
  for (std::size_t row = 0; row < display_.size(); ++row) {
    if (!all && display_[row] == shown_[row]) continue;
    // DCP 5.7 example 1: line, cursor position 0, 20 characters.
    std::array<std::uint8_t, 22> body{};
    body[0] = static_cast<std::uint8_t>(dcp::channel_char::kLine1 + row);
    body[1] = dcp::channel_char::kCursor0;
    for (std::size_t i = 0; i < 20; ++i) body[2 + i] = static_cast<std::uint8_t>(display_[row][i]);
    if (out_.push_message(dcp::channel_char::kModeRemote, body)) shown_[row] = display_[row];
  }
}

}  // namespace liftd::dcp::sim
