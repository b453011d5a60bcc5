// Light units. glTF files and the protocol speak photometry, as KHR_lights_punctual and
// KHR_materials_emissive_strength define it: point and spot intensity in candela (lm/sr),
// directional illuminance in lux (lm/m^2), emission in nits (cd/m^2). The renderer works in the
// matching radiometric quantities (W/sr, W/m^2, W/(m^2 sr)), converted at the spec's fixed
// luminous efficacy of 683 lm/W (docs/methods.md, "Units").
#pragma once

namespace bounce::scene {

inline constexpr double kLumensPerWatt = 683.0;

// candela -> W/sr, lux -> W/m^2, nits -> W/(m^2 sr)
constexpr double radiometric_from_photometric(double photometric) { return photometric / kLumensPerWatt; }
// W/sr -> candela, W/m^2 -> lux, W/(m^2 sr) -> nits
constexpr double photometric_from_radiometric(double radiometric) { return radiometric * kLumensPerWatt; }

}  // namespace bounce::scene
