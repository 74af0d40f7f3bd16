#include "sch001/card_link.hpp"

#include <type_traits>
#include <variant>

namespace liftd::sch001 {

CardLink::CardLink(const CardLinkConfig& config, MonoTime start) noexcept
    : config_(config), last_heard_(start) {}

bool CardLink::travel_allowed() const noexcept {
  return status_ && !silent_ && !status_->err && status_->rdy;
}

LinkChange CardLink::heard_at(MonoTime now) noexcept {
  last_heard_ = now;
  LinkChange change = LinkChange::None;
  if (!heard_) change = LinkChange::FirstHeard;
  if (silent_) change = LinkChange::Recovered;
  heard_ = true;
  ever_heard_ = true;
  silent_ = false;
  return change;
}

void CardLink::endpoint_reopened(MonoTime now) noexcept {
  status_.reset();
  heard_ = false;
  silent_ = false;
  timeout_enabled_ = true;
  last_heard_ = now;
}

FrameResult CardLink::on_frame(const can::Frame& frame, MonoTime now) noexcept {
  FrameResult result;
  if (frame.id == config_.ids.to_card) {
    ++counters_.own_id;  // another node on our identifier: a bus set-up error, never acted on
    return result;
  }
  if (frame.id != config_.ids.from_card) {
    ++counters_.other_id;
    return result;
  }
  const CardMessage message = decode_card_frame(frame);
  if (const auto* rejection = std::get_if<Rejection>(&message)) {
    // Not information from the card: it neither answers nor resets the timeout.
    if (*rejection == Rejection::WrongLength) {
      ++counters_.wrong_length;
    } else {
      ++counters_.unknown_first_byte;
    }
    return result;
  }
  result.change = heard_at(now);
  if (const auto* timeout = std::get_if<TimeoutCommand>(&message)) {
    ++counters_.timeout_commands;
    timeout_enabled_ = timeout->enable;
    result.answer = encode_timeout_ack(config_.ids, timeout->enable);
    ++counters_.answers;
    return result;
  }
  const CardStatus status = std::get<StatusFrame>(message).status;
  ++counters_.status_frames;
  result.status_changed = !status_ || !(*status_ == status);
  status_ = status;
  Command out = command_;
  // 3d, 3e: travel commands only without ERR and with RDY; judged on the status this frame
  // brought, so a falling RDY drops them in this very answer.
  if (!travel_allowed()) out.bits = CommandBits{};
  result.answer = encode_command(config_.ids, out);
  ++counters_.answers;
  return result;
}

LinkChange CardLink::on_tick(MonoTime now) noexcept {
  if (!timeout_enabled_ || silent_ || now - last_heard_ < kCardTimeout) return LinkChange::None;
  silent_ = true;
  ++counters_.timeouts;
  return LinkChange::Silent;
}

}  // namespace liftd::sch001
