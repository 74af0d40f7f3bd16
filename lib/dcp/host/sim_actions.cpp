#include "dcp/host/sim_actions.hpp"

#include "dcp/registry_entry.hpp"

#include <optional>
#include <string>

#include "api/result.hpp"
#include "api/schema.hpp"

namespace liftd::daemon {
namespace {

api::ArgSchema dcp_sim_args() {
  return {api::choice_arg("channel", false, api::names_of(kSimChannelFaults),
                          "channel_fault: the communication-channel fault to inject")};
}

std::optional<api::Result> check_dcp_sim_request(std::size_t own, const nlohmann::json& request) {
  if (static_cast<DcpSimAction>(own) == DcpSimAction::ChannelFault &&
      !request.contains("channel")) {
    return api::Result::fail(api::ErrorCode::BadRequest, "channel_fault needs a channel",
                             "channel");
  }
  return std::nullopt;
}

}  // namespace

DcpSimRequest dcp_sim_request(const api::SimRequest& request) {
  DcpSimRequest out;
  out.action = static_cast<DcpSimAction>(request.own);
  if (out.action == DcpSimAction::ChannelFault) {
    out.channel = api::enum_of<SimChannelFault>(kSimChannelFaults,
                                                request.request.at("channel").get<std::string>());
  }
  return out;
}

const api::KindSimActions kDcpSimActionTable = {drive::Kind::Dcp,     "DCP",
                                                api::kEverySimAction, kDcpSimActions,
                                                dcp_sim_args,         check_dcp_sim_request};

}  // namespace liftd::daemon

namespace liftd::dcp {

const api::KindSimActions& RegistryEntry::sim_actions() noexcept {
  return daemon::kDcpSimActionTable;
}

}  // namespace liftd::dcp
