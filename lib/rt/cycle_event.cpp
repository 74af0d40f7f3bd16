#include "rt/cycle_event.hpp"

#include <cstring>

namespace liftd::rt {

std::string describe(const CycleEvent& event) {
  const std::string text(event.text.data());
  switch (event.kind) {
    case CycleEventKind::ThreadStatus:
      return "cycle thread: " + text;
    case CycleEventKind::PortOpened:
      return "serial port opened: " + text;
    case CycleEventKind::PortOpenFailed:
      return "serial port open failed, retrying: " + text;
    case CycleEventKind::PortLost:
      return "serial port lost" +
             (event.count > 1 ? " " + std::to_string(event.count) + " times, the last" : "") +
             " (" +
             std::string(event.error_number != 0 ? std::strerror(event.error_number) : "hang-up") +
             "), reopening";
    case CycleEventKind::SkipRunStarted:
      return "cycle overrun: woke " + std::to_string(event.lateness.count() / 1000) +
             " us late, beyond the send window; " + std::to_string(event.count) +
             " cycle(s) skipped";
    case CycleEventKind::SkipRunEnded:
      return "cycle overrun ended: " + std::to_string(event.count) +
             " cycle(s) skipped in the run, worst wake-up " +
             std::to_string(event.lateness.count() / 1000) + " us late";
    case CycleEventKind::LineEcho:
      return event.count != 0
                 ? "the serial line echoes: each frame sent comes back before the reply and is "
                   "read back and checked (drive.echo auto)"
                 : "the serial line does not echo (drive.echo auto)";
  }
  return "unknown cycle event";
}

}  // namespace liftd::rt
