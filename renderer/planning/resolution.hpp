// Rendering smaller and upsampling, a knob the planner plans like the others: a GPU frame at half
// or a quarter of the size costs the device line at its own pixels, and adds what upsampling loses.
// That loss is measured on the scene, per method: its draft frame at each scale, upsampled, against
// its full-size draft frame. Per method, because each loses differently: on the Cornell box at 64
// pixels, half size loses 0.20 of relMSE for direct and 0.27 to 0.38 for vct, isr and cssm (their
// indirect light puts edges where direct light leaves black), while presets of one method differ
// by under 10%.
#pragma once

#include "renderer/planning/costs.hpp"
#include "renderer/renderer.hpp"

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace bounce::planning {

inline constexpr double kFrameScales[] = {0.5, 0.25};
inline constexpr int kMinScaledSide = 16;  // smaller frames are not offered

// The size a frame of width x height renders at, at `scale`; at least one pixel a side.
std::pair<int, int> scaled_size(int width, int height, double scale);

// The size upsampling's loss is measured at for frames of width x height: theirs, or, past
// kMeasuredSide on the longer side, the same shape that long, so that a client cannot make the
// measurement cost more than frames of that size. A smaller frame has more of its pixels on edges
// and loses more there: for edges, the loss measured is on the safe side (not for fine texture
// that only the larger frame resolves).
inline constexpr int kMeasuredSide = 256;
std::pair<int, int> measured_size(int width, int height);

// Per method of `methods` (GPU methods): relMSE of upsampling at each scale of kFrameScales whose
// frame keeps kMinScaledSide a side, from its draft frames of `view` on the render thread. With
// `measurements` and `device`, the draft frames' times are recorded there too (the full-size one
// from a second, warm frame): frames of one preset at three sizes give the scene its own cost line
// (SceneMeasurements::line), which prices every size the planner offers.
using ResampleErrors = std::map<std::string, std::map<double, double>>;
ResampleErrors measure_resample_errors(Renderer& renderer, SceneResources& resources, const RenderRequest& view,
                                       const std::vector<std::string>& methods, SceneMeasurements* measurements = nullptr,
                                       const DeviceCosts* device = nullptr);

// A frame rendered at a smaller size, upsampled to width x height, with its display image remade
// from the upsampled radiance when the request asks for one.
RenderResult upsampled(const RenderResult& rendered, int width, int height, const RenderRequest& request);

}  // namespace bounce::planning
