// Requests that wait for one piece of long CPU work a frame needs (a method's PendingWork, such as
// the cssm bake), run once off the render thread however many requests need it. The work goes on
// while any of them still wants it (not cancelled, not past its timeout_ms) and tells each one its
// progress.
#pragma once

#include "server/request.hpp"

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace bounce::server {

class SharedWork {
public:
    void add(std::shared_ptr<Request> request);
    // From the worker: sends `progress` events (at most five a second, and the last) to the waiters
    // that still want the work; false when none does, which stops the work.
    bool progress(double fraction, const std::string& stage);
    // Every waiter, once the work has ended; later calls return none.
    std::vector<std::shared_ptr<Request>> take();

private:
    std::mutex mutex_;
    std::vector<std::shared_ptr<Request>> waiters_;
    Request::Clock::time_point last_sent_{};
};

}  // namespace bounce::server
