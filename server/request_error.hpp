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

// What an exception thrown while serving a request means to the client: the code, the message and
// the offending field. Unexpected exceptions are `internal`.
struct Failure {
    protocol::ErrorCode code = protocol::ErrorCode::internal;
    std::string message;
    std::optional<std::string> field;
};
Failure describe_failure(std::exception_ptr error);

}  // namespace bounce::server
