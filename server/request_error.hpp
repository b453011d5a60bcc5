// An error a request earns, with the protocol error code that answers it.
#pragma once

#include "protocol/protocol.hpp"
#include "renderer/base/error.hpp"

#include <optional>
#include <string>

namespace bounce::server {

class RequestError : public Error {
public:
    RequestError(protocol::ErrorCode code, const std::string& message, std::optional<std::string> field = {})
        : Error(message), code_(code), field_(std::move(field)) {}
    protocol::ErrorCode code() const { return code_; }
    const std::optional<std::string>& field() const { return field_; }

private:
    protocol::ErrorCode code_;
    std::optional<std::string> field_;
};

}  // namespace bounce::server
