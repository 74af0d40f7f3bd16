// spdlog wiring: one spdlog logger per component sharing one sink (journal or text). The event
// name and extra fields travel to the sink through a thread-local context, which is sound
// because these loggers are synchronous: the sink runs on the calling thread.
#include "log/log.hpp"

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>

#include <spdlog/logger.h>
#include <spdlog/sinks/base_sink.h>

#include "log/journal.hpp"

namespace liftd::log {
namespace {

struct Context {
  std::string_view event;
  const Fields* fields = nullptr;
  std::string_view function;
  std::optional<Catalogued> catalogued;
};
thread_local const Context* t_context = nullptr;

std::string_view view(spdlog::string_view_t text) {
  return {text.data(), text.size()};
}

Level from_spdlog(spdlog::level::level_enum level) {
  switch (level) {
    case spdlog::level::trace:
      return Level::trace;
    case spdlog::level::debug:
      return Level::debug;
    case spdlog::level::info:
      return Level::info;
    case spdlog::level::warn:
      return Level::warn;
    default:
      return Level::error;
  }
}

spdlog::level::level_enum to_spdlog(Level level) {
  switch (level) {
    case Level::trace:
      return spdlog::level::trace;
    case Level::debug:
      return spdlog::level::debug;
    case Level::info:
      return spdlog::level::info;
    case Level::warn:
      return spdlog::level::warn;
    case Level::error:
      return spdlog::level::err;
  }
  return spdlog::level::info;
}

Record make_record(const spdlog::details::log_msg& msg) {
  Record record;
  record.level = from_spdlog(msg.level);
  record.component = view(msg.logger_name);
  record.text = view(msg.payload);
  if (msg.source.filename != nullptr && msg.source.line > 0) {
    record.file = msg.source.filename;
    record.line = static_cast<unsigned>(msg.source.line);
  }
  if (t_context != nullptr) {
    record.event = t_context->event;
    record.fields = t_context->fields;
    record.function = t_context->function;
    record.catalogued = t_context->catalogued;
  }
  return record;
}

void write_stderr_line(std::string line) {
  line += '\n';
  std::fwrite(line.data(), 1, line.size(), stderr);
}

class TextSink final : public spdlog::sinks::base_sink<std::mutex> {
 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    write_stderr_line(format_text_line(make_record(msg), msg.time));
  }
  void flush_() override { std::fflush(stderr); }
};

class JournalSink final : public spdlog::sinks::base_sink<std::mutex> {
 public:
  explicit JournalSink(std::string identifier) : identifier_(std::move(identifier)) {}

 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    const Record record = make_record(msg);
    const int error = send_to_journal(journal_fields(record, identifier_));
    if (error == 0) return;
    // journald is unreachable: keep the record on stderr, with its priority as a "<N>" prefix
    // (systemd's stdout/stderr stream and syslog readers both honour it).
    if (!reported_failure_) {
      reported_failure_ = true;
      write_stderr_line("<4>liftd: cannot write to the journal: " +
                        std::string(std::strerror(error)) + "; logging to stderr");
    }
    write_stderr_line(format_stream_line(record));
  }
  void flush_() override { std::fflush(stderr); }

 private:
  std::string identifier_;
  bool reported_failure_ = false;
};

struct State {
  std::mutex mutex;
  spdlog::sink_ptr sink = std::make_shared<TextSink>();
  std::map<std::string, std::shared_ptr<spdlog::logger>, std::less<>> loggers;
};

State& state() {
  static State s;
  return s;
}

std::atomic<Level> g_level{Level::info};

std::shared_ptr<spdlog::logger> logger_for(std::string_view component) {
  State& s = state();
  std::lock_guard lock(s.mutex);
  auto it = s.loggers.find(component);
  if (it == s.loggers.end()) {
    auto logger = std::make_shared<spdlog::logger>(std::string(component), s.sink);
    logger->set_level(spdlog::level::trace);  // filtering happens in enabled()
    it = s.loggers.emplace(std::string(component), std::move(logger)).first;
  }
  return it->second;
}

void emit(Level level, std::string_view component, const Context& context, std::string_view text,
          const std::source_location& where) {
  const auto logger = logger_for(component);
  const Context* previous = t_context;
  t_context = &context;
  const spdlog::source_loc location =
      where.line() == 0 ? spdlog::source_loc{}
                        : spdlog::source_loc{where.file_name(), static_cast<int>(where.line()),
                                             where.function_name()};
  logger->log(location, to_spdlog(level), spdlog::string_view_t(text.data(), text.size()));
  t_context = previous;
}

}  // namespace

std::string_view to_string(Level level) {
  switch (level) {
    case Level::trace:
      return "trace";
    case Level::debug:
      return "debug";
    case Level::info:
      return "info";
    case Level::warn:
      return "warn";
    case Level::error:
      return "error";
  }
  return "info";
}

std::optional<Level> parse_level(std::string_view name) {
  for (Level l : {Level::trace, Level::debug, Level::info, Level::warn, Level::error}) {
    if (to_string(l) == name) return l;
  }
  return std::nullopt;
}

bool under_systemd() {
  const char* stream = std::getenv("JOURNAL_STREAM");
  const char* invocation = std::getenv("INVOCATION_ID");
  return (stream != nullptr && *stream != '\0') || (invocation != nullptr && *invocation != '\0');
}

Backend resolve(Backend backend) {
  if (backend != Backend::automatic) return backend;
  return under_systemd() ? Backend::journal : Backend::text;
}

void init(const Options& options) {
  spdlog::sink_ptr sink;
  if (resolve(options.backend) == Backend::journal) {
    sink = std::make_shared<JournalSink>(options.identifier);
  } else {
    sink = std::make_shared<TextSink>();
  }
  State& s = state();
  {
    std::lock_guard lock(s.mutex);
    s.sink = sink;
    for (auto& [name, logger] : s.loggers) logger->sinks().assign(1, sink);
  }
  set_level(options.level);
}

void set_level(Level level) {
  g_level.store(level, std::memory_order_relaxed);
}

Level level() {
  return g_level.load(std::memory_order_relaxed);
}

bool enabled(Level level) {
  return static_cast<int>(level) >= static_cast<int>(g_level.load(std::memory_order_relaxed));
}

void flush() {
  State& s = state();
  std::lock_guard lock(s.mutex);
  s.sink->flush();
}

void event(Level level, std::string_view component, std::string_view event_name,
           const Fields& fields, std::string_view text, std::optional<Catalogued> catalogued,
           std::source_location where) {
  if (!enabled(level)) return;
  const Context context{event_name, &fields, where.function_name(), catalogued};
  emit(level, component, context, text, where);
}

void write(Level level, std::string_view component, std::string_view text,
           std::source_location where) {
  if (!enabled(level)) return;
  const Context context{{}, nullptr, where.line() == 0 ? "" : where.function_name(), std::nullopt};
  emit(level, component, context, text, where);
}

}  // namespace liftd::log
