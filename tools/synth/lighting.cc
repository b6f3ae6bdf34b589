#include "tools/synth/lighting.h"

#include <cmath>

namespace aprt::synth {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

Vec3 sun_direction(double azimuth_deg, double elevation_deg) {
  const double az = azimuth_deg * kPi / 180, el = elevation_deg * kPi / 180;
  return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
}

std::optional<Lighting> lighting_preset(std::string_view name) {
  Lighting L;           // the defaults are the day preset's colours
  if (name == "day") {  // sun at azimuth 135 deg, 50 deg up
    L.sun_dir = sun_direction(135, 50);
  } else if (name == "dusk") {  // low orange sun (azimuth 250 deg from east), purple sky
    L.sun_dir = sun_direction(250, 14);
    L.sun = {1.0f, 0.62f, 0.35f};
    L.ambient = {0.22f, 0.2f, 0.28f};
    L.sky_horizon = {0.95f, 0.6f, 0.4f};
    L.sky_zenith = {0.25f, 0.3f, 0.55f};
    L.fog = {0.7f, 0.55f, 0.5f};
    L.fog_distance = 220.0;
  } else if (name == "overcast") {  // weak diffuse sun, grey sky, haze
    L.sun_dir = sun_direction(200, 60);
    L.sun = {0.25f, 0.25f, 0.27f};
    L.ambient = {0.62f, 0.63f, 0.66f};
    L.sky_horizon = {0.78f, 0.79f, 0.8f};
    L.sky_zenith = {0.6f, 0.62f, 0.66f};
    L.fog = {0.72f, 0.73f, 0.75f};
    L.fog_distance = 140.0;
  } else if (name == "morning") {  // low pale-yellow sun (azimuth 70 deg)
    L.sun_dir = sun_direction(70, 22);
    L.sun = {1.0f, 0.9f, 0.74f};
    L.ambient = {0.3f, 0.33f, 0.4f};
    L.sky_horizon = {0.86f, 0.86f, 0.84f};
    L.sky_zenith = {0.42f, 0.56f, 0.82f};
    L.fog = {0.82f, 0.83f, 0.85f};
    L.fog_distance = 350.0;
  } else if (name == "noon") {  // high bright sun (azimuth 270 deg), short shadows
    L.sun_dir = sun_direction(270, 72);
    L.sun = {1.05f, 1.02f, 0.96f};
    L.ambient = {0.36f, 0.39f, 0.45f};
    L.fog_distance = 900.0;
  } else if (name == "haze") {  // milky light, weak sun (azimuth 300 deg), thick haze
    L.sun_dir = sun_direction(300, 35);
    L.sun = {0.55f, 0.53f, 0.5f};
    L.ambient = {0.48f, 0.47f, 0.46f};
    L.sky_horizon = {0.85f, 0.83f, 0.78f};
    L.sky_zenith = {0.7f, 0.72f, 0.75f};
    L.fog = {0.8f, 0.78f, 0.74f};
    L.fog_distance = 110.0;
  } else if (name == "night") {  // no sun: street lights, headlights, a faint moonlit sky
    L.sun_dir = sun_direction(30, 40);
    L.sun = {0.025f, 0.027f, 0.04f};
    L.ambient = {0.02f, 0.022f, 0.035f};
    L.sky_horizon = {0.06f, 0.055f, 0.08f};
    L.sky_zenith = {0.01f, 0.012f, 0.03f};
    L.fog = {0.05f, 0.045f, 0.05f};
    L.fog_distance = 300.0;
    L.lamp_intensity = 7.0;
    L.headlight = 0.45;
  } else {
    return std::nullopt;
  }
  return L;
}

}  // namespace aprt::synth
