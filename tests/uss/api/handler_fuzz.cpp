// libFuzzer target: one request line through a USS lift's dispatcher (no socket), with the USS
// fake serving the USS lift's own commands, so that their handlers run to the backend
// (lib/uss/host/commands.cpp: the PKW arguments, a value that fits no word). The oracle is the
// API handler targets' (tests/api/handler_fuzz.hpp): exactly one reply line, never a crash.
#include <cstdint>

#include "api/handler_fuzz.hpp"
#include "uss/api/fake_uss_backend.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return liftd::api::testing::fuzz_one_request<liftd::api::testing::FakeUssBackend>(data, size);
}
