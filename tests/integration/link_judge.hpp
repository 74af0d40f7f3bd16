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
/// 40 s. Then every restart must have followed a lost reply, and the lost replies must be
/// within the machine's share unless the test itself withheld replies just before: 1 % of the
/// cycles, at least 2, beyond twice what the reference link lost for each pty the master's
/// exchanges cross (`ptys`: 1 with the drive on the far end of the master's pty, 2 with a relay
/// between two; the reference link crosses one, and each crossing is a flip-buffer delivery
/// the machine can hold up).
inline ::testing::AssertionResult ready_within(LiveMaster& m,
                                               const liftd::testing::ReferenceLink& reference,
                                               std::chrono::milliseconds base,
                                               bool losses_injected = false, unsigned ptys = 1) {
  const dcp::LinkCounters from = m.controller.snapshot().link_counters;
  const std::uint64_t cycles_from = m.runner.stats().counters.cycles;
  const MonoTime began = mono_now();
  const auto restarts = [&] {
    return m.controller.snapshot().link_counters.request_timeouts - from.request_timeouts;
  };
  while (!m.wait_until([&] { return m.ready(); }, std::chrono::milliseconds(250))) {
    const MonoTime allowed =
        began + base + std::chrono::milliseconds(1500 * std::min<std::uint64_t>(20, restarts()));
    if (mono_now() > std::min(allowed, began + std::chrono::milliseconds(40000))) {
      return ::testing::AssertionFailure()
             << "the link is not up in the time allowed; handshake restarts: " << restarts()
             << "; reference link: " << reference.missing() << " of " << reference.exchanges()
             << " missed\n"
             << tail_of_trace(m.runner, 80);
    }
  }
  const std::uint64_t lost =
      m.controller.snapshot().link_counters.missing_replies - from.missing_replies;
  if (restarts() > lost) {
    return ::testing::AssertionFailure()
           << restarts() << " handshake restarts but only " << lost << " lost replies";
  }
  const std::uint64_t share =
      std::max<std::uint64_t>(2, (m.runner.stats().counters.cycles - cycles_from) / 100) +
      2 * ptys * reference.missing();
  if (!losses_injected && lost > share) {
    return ::testing::AssertionFailure() << lost << " replies lost before the link was up, "
                                         << "more than the machine's share " << share
                                         << " (reference link: " << reference.missing() << " of "
                                         << reference.exchanges() << " missed)";
  }
  return ::testing::AssertionSuccess();
}

}  // namespace liftd::integration
