// Named lighting conditions of the synthetic town. The training drives use
// day, overcast, morning and noon; haze is kept for validation under a light
// the model was not trained on; dusk is the test drive's and in no training
// or validation set (docs/evaluation.md: the paper's split principle); night
// (street lights and headlights only) is the LiDAR comparison's test light.
#pragma once

#include <optional>
#include <string_view>

#include "tools/synth/raycast.h"

namespace aprt::synth {

// The preset of that name, or nullopt for a name that is none of kLightingNames.
std::optional<Lighting> lighting_preset(std::string_view name);

// Unit vector towards a sun at that azimuth (degrees from +x east,
// counter-clockwise) and elevation (degrees above the horizon).
Vec3 sun_direction(double azimuth_deg, double elevation_deg);

inline constexpr const char* kLightingNames = "day|overcast|morning|noon|haze|dusk|night";

}  // namespace aprt::synth
