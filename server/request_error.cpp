#include "server/request_error.hpp"

namespace bounce::server {

Failure describe_failure(std::exception_ptr error) {
    try {
        std::rethrow_exception(error);
    } catch (const RequestError& e) {
        return {e.code(), e.what(), e.field()};
    } catch (const protocol::FieldError& e) {
        return {protocol::ErrorCode::bad_request, e.what(), e.field};
    } catch (const protocol::ProtocolError& e) {
        return {e.code, e.what(), std::nullopt};
    } catch (const ResourceExhausted& e) {
        return {protocol::ErrorCode::resource_exhausted, e.what(), std::nullopt};
    } catch (const Cancelled& e) {
        return {protocol::ErrorCode::cancelled, e.what(), std::nullopt};
    } catch (const InputError& e) {
        return {protocol::ErrorCode::bad_request, e.what(), std::nullopt};
    } catch (const std::exception& e) {
        return {protocol::ErrorCode::internal, e.what(), std::nullopt};
    } catch (...) {
        return {protocol::ErrorCode::internal, "unknown failure", std::nullopt};
    }
}

}  // namespace bounce::server
