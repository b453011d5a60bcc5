#include "server/stream_ladder.hpp"

#include "renderer/image/codec.hpp"
#include "renderer/methods/registry.hpp"
#include "server/request_error.hpp"

#include <algorithm>
#include <cmath>

namespace bounce::server {
namespace {

using nlohmann::json;
using protocol::FieldError;

// Re-plans a rung after its request changed; a rung the registry refuses is the stream's fault.
void replan(RenderOrder& frame, const char* field) {
    try {
        frame.plan = plan_frame(frame.request);
    } catch (const InputError& error) {
        throw FieldError(field, error.what());
    }
}

bool same_frame(const RenderOrder& a, const RenderOrder& b) {
    return a.request.method == b.request.method && a.request.preset == b.request.preset &&
           a.plan.knobs == b.plan.knobs && a.request.width == b.request.width &&
           a.request.height == b.request.height && a.jpeg_quality == b.jpeg_quality;
}

}  // namespace

std::vector<Rung> build_ladder(const StreamOrder& order) {
    std::vector<Rung> ladder;

    Rung interactive{"interactive", order.view};
    RenderRequest& quick = interactive.frame.request;
    quick.width = std::max(1, static_cast<int>(std::lround(order.view.request.width * order.interactive_scale)));
    quick.height = std::max(1, static_cast<int>(std::lround(order.view.request.height * order.interactive_scale)));
    interactive.frame.jpeg_quality = order.interactive_quality;
    // With a budget, the interactive and still rungs are planned for it, each at its own size, when
    // they render (RequestHandlers::plan_budgeted); without, the quick rung is the draft preset.
    if (!order.view.budget) {
        quick.preset = "draft";
        if (quick.method == "reference") quick.knobs["denoise"] = 1;  // one sample's noise is no preview
        replan(interactive.frame, "method");
    }
    ladder.push_back(std::move(interactive));

    Rung still{"still", order.view};
    if (!same_frame(still.frame, ladder.front().frame)) ladder.push_back(std::move(still));
    if (!order.refine) return ladder;

    // Each rung afresh at four times the last one's samples: the ladder's total is about 4/3 of its
    // last rung, and every rung but the last is denoised, which beats four times the samples
    // unfiltered (docs/benchmarks.md, "Denoiser").
    std::vector<int> samples;
    for (int spp = kFirstReferenceSpp; spp < order.reference_spp; spp *= kReferenceSppStep) samples.push_back(spp);
    samples.push_back(order.reference_spp);
    for (std::size_t i = 0; i < samples.size(); ++i) {
        Rung reference{"reference", order.view};
        reference.frame.budget.reset();  // the ladder's top converges whatever the budget
        RenderRequest& request = reference.frame.request;
        request.method = "reference";
        request.preset = "medium";
        request.knobs = {{"spp", samples[i]},
                         {"seed", static_cast<double>(ladder.size())},
                         {"denoise", i + 1 < samples.size() ? 1.0 : 0.0}};
        replan(reference.frame, "reference_spp");
        ladder.push_back(std::move(reference));
    }
    return ladder;
}

StreamOrder parse_stream(const json& fields, std::uint64_t max_pixels) {
    if (!fields.is_object()) throw FieldError("stream", "a stream's fields must be a JSON object");
    for (const char* refused : {"min_scene_version", "timeout_ms"}) {
        if (fields.contains(refused)) {
            throw FieldError(refused, fmt::format("field '{}' is a render's, not a stream's (yet)", refused));
        }
    }
    json body = fields;
    if (!body.contains("format")) body["format"] = "jpeg";
    StreamOrder order;
    order.view = parse_render(body, max_pixels);
    if (image::parse_image_format(order.view.format) == image::ImageFormat::exr) {
        throw FieldError("format", "a stream sends display images: format png, jpeg or webp");
    }
    order.refine = protocol::get_optional_bool(body, "refine").value_or(true);
    order.reference_spp = static_cast<int>(protocol::get_optional_integer(body, "reference_spp", 1, 65536).value_or(256));
    if (const auto scale = protocol::get_optional_number(body, "interactive_scale")) {
        if (!(*scale >= 0.05 && *scale <= 1.0)) {
            throw FieldError("interactive_scale", fmt::format("field 'interactive_scale' is {}, outside [0.05, 1]", *scale));
        }
        order.interactive_scale = *scale;
    }
    order.interactive_quality =
        static_cast<int>(protocol::get_optional_integer(body, "interactive_quality", 1, 100).value_or(50));
    order.ladder = build_ladder(order);
    return order;
}

}  // namespace bounce::server
