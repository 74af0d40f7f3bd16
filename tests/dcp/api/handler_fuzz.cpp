// libFuzzer target: one request line through a DCP lift's dispatcher (no socket), with the DCP
// fake serving the DCP lift's own commands, so that their handlers run to the backend
// (lib/dcp/host/commands.cpp: e.g. fast_start's "arm needs a floor"). The oracle is the API
// handler targets' (tests/api/handler_fuzz.hpp): exactly one reply line, never a crash.
#include <cstdint>

#include "api/handler_fuzz.hpp"
#include "dcp/api/fake_dcp_backend.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return liftd::api::testing::fuzz_one_request<liftd::api::testing::FakeDcpBackend>(data, size);
}
