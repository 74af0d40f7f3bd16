// How the live link tests judge a link on a shared machine: the machine's own share of lost
// replies is measured beside the test by a reference link (tests/support/reference_link.hpp),
// and the handshake is given the time its restarts need (DCP 5.12.2).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <sstream>
#include <string>

#include "dcp/trace.hpp"
#include "live_rig.hpp"
#include "support/reference_link.hpp"
#include "support/stall_judge.hpp"

namespace liftd::integration {

/// On failure, the last `n` recorded frames, decoded, help to see what the link did.
inline std::string tail_of_trace(const rt::CycleRunner& runner, std::size_t n = 40) {
  const auto records = runner.recorder().copy();
  const std::size_t from = records.size() > n ? records.size() - n : 0;
  std::ostringstream out;
  rt::write_text(out, std::span(records).subspan(from), dcp::trace_decoder());
  return out.str();
}

/// The machine's own share of late replies, measured beside a live link over the same time: a
/// bare link through a pty of its own at the cycle's priority. A reply the machine held up in
/// the tty's flip-buffer worker is lost to both alike.
inline int start_reference(liftd::testing::ReferenceLink& reference) {
  return reference.start(cycle_config("").thread.priority, false);
}

/// Waits until the link is up and the drive ready. The handshake (STX ETX, I0, I1, I3) takes
/// some 60 clean frames. A reply the machine held up loses the channel bytes it carried (DCP
/// 5.1), the message arrives spoilt, and the master rightly starts the handshake again after
/// the request's timeout (DCP 5.12.2): `base`, and 1.5 s more for every such restart, at most
/// 40 s. Then every restart must have followed a lost reply. How many replies the machine may
/// lose is judged by the long tests over thousands of cycles against the reference link: a
/// handshake of a few dozen frames is too short for a share (under two CPU hogs it lost 3 where
/// the reference link, sampling other instants, lost none of 29, and 13 where it lost 5 of 251).
inline ::testing::AssertionResult ready_within(LiveMaster& m,
                                               const liftd::testing::ReferenceLink& reference,
                                               std::chrono::milliseconds base) {
  const dcp::LinkCounters from = m.controller.snapshot().link_counters;
  const MonoTime began = mono_now();
  // Handshakes begun again: after a request's timeout (DCP 5.12.2), or at rest after a channel
  // fault a spoilt message caused (DCP 5.4); handshake_attempts counts those begun since the
  // last one that succeeded.
  const auto restarts = [&] {
    const dcp::LinkCounters now = m.controller.snapshot().link_counters;
    const std::uint64_t begun = now.handshake_attempts > 0 ? now.handshake_attempts - 1 : 0;
    return std::max<std::uint64_t>(now.request_timeouts - from.request_timeouts, begun);
  };
  while (!m.wait_until([&] { return m.ready(); }, std::chrono::milliseconds(250))) {
    const MonoTime allowed =
        began + base + std::chrono::milliseconds(1500 * std::min<std::uint64_t>(20, restarts()));
    if (mono_now() > std::min(allowed, began + std::chrono::milliseconds(40000))) {
      const auto snapshot = m.controller.snapshot();
      const dcp::LinkCounters& now = snapshot.link_counters;
      return ::testing::AssertionFailure()
             << "the link is not up in the time allowed: " << dcp::to_string(snapshot.link)
             << "; handshake restarts " << restarts() << ", handshakes started "
             << now.handshake_attempts << ", link faults " << now.link_faults - from.link_faults
             << ", replies good " << now.good_replies - from.good_replies << " missing "
             << now.missing_replies - from.missing_replies << " bad "
             << now.bad_checksum - from.bad_checksum << " (longest run " << now.longest_error_run
             << "), cycles skipped " << m.runner.stats().counters.skipped_cycles
             << "; reference link: " << reference.missing() << " of " << reference.exchanges()
             << " missed, " << reference.skipped() << " skipped, at most "
             << reference.longest_miss_run() << " in a row\n"
             << tail_of_trace(m.runner, 80);
    }
  }
  const dcp::LinkCounters now = m.controller.snapshot().link_counters;
  const std::uint64_t lost =
      now.missing_replies - from.missing_replies + (now.bad_checksum - from.bad_checksum);
  if (now.request_timeouts - from.request_timeouts > lost) {
    return ::testing::AssertionFailure()
           << now.request_timeouts - from.request_timeouts << " handshake restarts but only "
           << lost << " lost or spoilt replies";
  }
  return ::testing::AssertionSuccess();
}

/// The reference link saw the machine stall: eight periods in a row without an exchange
/// (docs/architecture.md), long enough for the link supervision to end a travel rightly.
inline bool machine_stalled(const liftd::testing::ReferenceLink& reference) {
  return reference.longest_miss_run() >= 8;
}

/// The master's own cycle was held up since `since`: two of its flight records more than eight
/// periods (DCP 7.2: 15 ms) apart while its port was open. The kernel can hold the cycle
/// thread in a tty call while the reference link's tty, another one, goes on (a drive
/// rightly stops a travel whose master falls silent that long).
inline bool cycle_stalled(const LiveMaster& m, MonoTime since) {
  constexpr auto kStall = 8 * std::chrono::milliseconds(15);
  const auto records = m.runner.recorder().copy();
  MonoTime last = since;
  for (const auto& rec : records) {
    if (rec.time < since) continue;
    if (rec.time - last > kStall) return true;
    last = rec.time;
  }
  return false;
}

/// A live link try's verdict (tests/support/stall_judge.hpp): the reference link or the
/// master's own cycle saw the machine stall since `since`.
inline liftd::testing::StallVerdict link_stall_verdict(
    const LiveMaster& m, const liftd::testing::ReferenceLink& reference, MonoTime since) {
  const bool cycle = cycle_stalled(m, since);
  const bool link = machine_stalled(reference);
  return {cycle || link, "reference link: at most " + std::to_string(reference.longest_miss_run()) +
                             " missed in a row; the cycle " + (cycle ? "was" : "was not") +
                             " held up"};
}

/// Sends a V4 travel to `floor` and waits until it finished and the car is idle. A travel a
/// link fault ended is run once more only if the reference link or the master's own cycle
/// witnessed a machine stall (then `*stall_seen` is set); never otherwise.
inline ::testing::AssertionResult travel_lands(LiveMaster& m,
                                               const liftd::testing::ReferenceLink& reference,
                                               std::size_t floor, bool* stall_seen = nullptr) {
  for (int attempt = 0; attempt < 2; ++attempt) {
    const std::size_t finished = m.travel_events(travel::Event::Type::Finished);
    const std::size_t aborted = m.travel_events(travel::Event::Type::Aborted);
    if (!m.wait_until([&] { return m.ready() && m.idle(); }, std::chrono::milliseconds(20000))) {
      return ::testing::AssertionFailure() << "not ready and idle before the travel\n"
                                           << tail_of_trace(m.runner);
    }
    const MonoTime began = mono_now();
    const control::CommandReply r =
        m.command(control::TravelCommand{floor, dcp::Speed::V4, std::nullopt, false});
    if (r.code != control::ReplyCode::Ok) return ::testing::AssertionFailure() << r.detail;
    const bool ended = m.wait_until(
        [&] {
          return (m.travel_events(travel::Event::Type::Finished) > finished ||
                  m.travel_events(travel::Event::Type::Aborted) > aborted) &&
                 m.idle();
        },
        std::chrono::milliseconds(40000));
    if (!ended) {
      return ::testing::AssertionFailure() << "the travel did not end\n" << tail_of_trace(m.runner);
    }
    if (m.travel_events(travel::Event::Type::Finished) > finished) {
      return ::testing::AssertionSuccess();
    }
    const bool stalled = machine_stalled(reference) || cycle_stalled(m, began);
    if (stall_seen != nullptr && stalled) *stall_seen = true;
    if (!stalled || attempt > 0) {
      return ::testing::AssertionFailure()
             << "travel aborted; reference link: at most " << reference.longest_miss_run()
             << " missed in a row; the cycle " << (stalled ? "was" : "was not") << " held up\n"
             << tail_of_trace(m.runner, 80);
    }
  }
  return ::testing::AssertionFailure() << "unreachable";
}

}  // namespace liftd::integration
