// An edge-avoiding à-trous wavelet filter for progressive `reference` frames (Dammertz, Sewtz,
// Hanika and Lensch 2010), guided by what the camera rays first met (PixelFeatures): a 5x5
// B-spline kernel applied `iterations` times with holes of 2^i pixels, each tap weighted by how
// alike the two pixels' colours (against their estimates' standard deviations, as SVGF does),
// normals and depths are. Radiance is divided by the first hit's
// albedo before filtering and multiplied back after, so textures stay sharp while the lighting is
// smoothed. The filter is normalized: a noise-free constant region comes back unchanged.
#pragma once

#include "renderer/image/frame.hpp"
#include "renderer/methods/reference/path_tracer.hpp"

namespace bounce::methods::reference {

// Defaults tuned on the built-in Cornell box at 128x128 (docs/methods.md gives the figures).
struct DenoiseSettings {
    int iterations = 5;         // the kernel's reach: 2^(iterations+1) pixels
    // Luminance difference, in standard deviations of the two pixels' estimates (SVGF's variance
    // guidance: the per-pixel sample variance, averaged over 3x3, carried through the passes), at
    // which a tap's weight falls to 1/e.
    float sigma_colour = 2.0f;
    float sigma_normal = 0.3f;  // normal difference (chord length) at which it falls to 1/e
    float sigma_depth = 0.05f;  // relative depth difference per pixel of hole at which it falls to 1/e
};

// Throws InputError when the frame and the features differ in size.
image::Frame denoise(const image::Frame& noisy, const PixelFeatures& features, const DenoiseSettings& settings = {});

}  // namespace bounce::methods::reference
