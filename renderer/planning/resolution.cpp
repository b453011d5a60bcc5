#include "renderer/planning/resolution.hpp"

#include "renderer/image/metrics.hpp"
#include "renderer/image/tone.hpp"
#include "renderer/planning/planner.hpp"

#include <algorithm>
#include <cmath>

namespace bounce::planning {

std::pair<int, int> scaled_size(int width, int height, double scale) {
    return {std::max(1, static_cast<int>(std::lround(width * scale))), std::max(1, static_cast<int>(std::lround(height * scale)))};
}

std::pair<int, int> measured_size(int width, int height) {
    const int longer = std::max(width, height);
    if (longer <= kMeasuredSide) return {width, height};
    return scaled_size(width, height, static_cast<double>(kMeasuredSide) / longer);
}

ResampleErrors measure_resample_errors(Renderer& renderer, SceneResources& resources, const RenderRequest& view,
                                       const std::vector<std::string>& methods, SceneMeasurements* measurements,
                                       const DeviceCosts* device) {
    ResampleErrors errors;
    const auto record = [&](const RenderResult& result, const RenderRequest& request) {
        if (measurements && device) {
            record_frame(*measurements, resources.analysis_if_made(), *device, result.stats, request.width, request.height);
        }
    };
    for (const std::string& method : methods) {
        RenderRequest draft = view;
        draft.method = method;
        draft.preset = "draft";
        draft.knobs.clear();
        draft.make_display_image = false;
        const image::Frame full = renderer.render(resources, draft).frame;  // may build the method's structures
        for (const double scale : kFrameScales) {
            RenderRequest small = draft;
            std::tie(small.width, small.height) = scaled_size(view.width, view.height, scale);
            if (std::min(small.width, small.height) < kMinScaledSide) continue;
            const RenderResult rendered = renderer.render(resources, small);
            record(rendered, small);
            errors[method][scale] = image::compare(image::resample_linear(rendered.frame, view.width, view.height), full).rel_mse;
        }
        if (measurements && device && errors.count(method)) record(renderer.render(resources, draft), draft);
    }
    return errors;
}

RenderResult upsampled(const RenderResult& rendered, int width, int height, const RenderRequest& request) {
    RenderResult result;
    result.stats = rendered.stats;
    result.frame = image::resample_linear(rendered.frame, width, height);
    if (request.make_display_image) image::make_display_image(result.frame, request.display);
    return result;
}

}  // namespace bounce::planning
