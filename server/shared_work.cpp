#include "server/shared_work.hpp"

namespace bounce::server {

void SharedWork::add(std::shared_ptr<Request> request) {
    std::lock_guard lock(mutex_);
    waiters_.push_back(std::move(request));
}

bool SharedWork::progress(double fraction, const std::string& stage) {
    std::lock_guard lock(mutex_);
    const auto now = Request::Clock::now();
    const bool send = now - last_sent_ >= std::chrono::milliseconds(200) || fraction >= 1.0;
    if (send) last_sent_ = now;
    bool wanted = false;
    for (const auto& request : waiters_) {
        if (request->is_cancelled() || now > request->deadline) continue;
        wanted = true;
        if (send) {
            request->send(protocol::make_message(protocol::MessageType::progress, request->id(),
                                                 {{"fraction", fraction}, {"stage", stage}}));
        }
    }
    return wanted;
}

std::vector<std::shared_ptr<Request>> SharedWork::take() {
    std::lock_guard lock(mutex_);
    return std::exchange(waiters_, {});
}

}  // namespace bounce::server
