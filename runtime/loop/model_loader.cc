#include "runtime/loop/model_loader.h"

#include <unistd.h>

#include "runtime/loop/model_signature.h"

namespace aprt {

ModelRequest model_request(const Config& config) {
  ModelRequest r;
  r.path = config.model;
  EngineOptions& eo = r.engine;
  eo.threads = config.engine.threads;
  eo.isa = config.engine.isa.c_str();
  eo.cpus = config.engine.cpus.empty() ? nullptr : config.engine.cpus.data();
  eo.n_cpus = int(config.engine.cpus.size());
  // The model's modality is checked against the configured source by
  // model_fits_source(), which can name the remedy.
  r.public_key = config.model_signing.public_key;
  r.require_signature = config.model_signing.required;
  return r;
}

Status model_fits_source(const ModelMeta& m, const Config::Source& src, const std::string& model,
                         int scans) {
  const bool lidar_model = m.modality != format::Modality::kImage;
  const bool lidar_source = scans < 0 ? src.lidar_source() : scans == 1;
  if (src.type == SourceType::kMcap && scans < 0) return ok();  // checked once the file is open
  if (lidar_source == lidar_model) return ok();
  if (src.type == SourceType::kMcap) {
    return Error(Errc::kWrongTarget, "run: %s is a %s model, but %s records %s", model.c_str(),
                 format::modality_name(m.modality), src.replay.path.c_str(),
                 lidar_source ? "LiDAR scans" : "camera frames");
  }
  return Error(Errc::kWrongTarget, "run: %s is a %s model, but source.type '%s' gives %s (%s)",
               model.c_str(), format::modality_name(m.modality), source_type_name(src.type),
               src.lidar_source() ? "LiDAR scans" : "camera frames",
               lidar_model ? "use lidar_replay or pointcloud2" : "use replay, v4l2 or libcamera");
}

Expected<std::unique_ptr<Engine>> load_model(const ModelRequest& request, std::string* note) {
  const char* path = request.path.c_str();
  // Without signatures the engine reads the file itself, piece by piece (the
  // peak is its block); a signature is checked over the very bytes loaded.
  if (request.public_key.empty()) return Engine::load_file(path, request.engine);
  auto bytes = Engine::read_model_file(path);
  if (!bytes) return bytes.error();
  {
    const std::string sig = signature_path(request.path);
    const bool has_sig = access(sig.c_str(), F_OK) == 0;
    if (!has_sig && request.require_signature) {
      return Error(Errc::kInvalidArgument,
                   "model: '%s' has no signature (%s) and model_signing.required is set; sign it "
                   "with `aprt sign %s --key KEY.key`",
                   path, sig.c_str(), path);
    }
    if (has_sig) {
      auto key = read_public_key(request.public_key);
      if (!key) return key.error();
      if (Status s = verify_signature(bytes->data(), bytes->size(), sig, *key); !s) {
        Error e = s.error();
        e.with_context("model '%s'", path);
        return e;
      }
      if (note) *note = "signature verified (" + sig + ")";
    } else if (note) {
      *note = "warning: no signature (" + sig + "); model_signing.required is off";
    }
  }
  auto e = Engine::load_memory(bytes->data(), bytes->size(), request.engine);
  if (!e) {
    Error err = e.error();
    err.with_context("%s", path);
    return err;
  }
  return e;
}

Status reload_compatible(const ModelMeta& running, const ModelMeta& next) {
  if (running.modality != next.modality) {
    return Error(Errc::kInvalidArgument,
                 "reload: the new model is a %s model, the running one %s; restart aprt to "
                 "change the sensor",
                 format::modality_name(next.modality), format::modality_name(running.modality));
  }
  // A LiDAR model's input is made with its file's geometry: the same or a restart.
  const bool same_bev = running.bev_cell_m == next.bev_cell_m &&
                        running.bev_x_min == next.bev_x_min &&
                        running.bev_y_min == next.bev_y_min &&
                        running.bev_height_threshold_m == next.bev_height_threshold_m &&
                        running.bev_clip_count == next.bev_clip_count;
  const bool same_points = running.points_crop_radius_m == next.points_crop_radius_m &&
                           running.points_coord_scale_m == next.points_coord_scale_m;
  if (!same_bev || !same_points) {
    return Error(Errc::kInvalidArgument,
                 "reload: the new model's LiDAR %s differs from the running one's; restart aprt "
                 "to change the preprocessing",
                 same_bev ? "crop or coordinate scale" : "histogram geometry");
  }
  for (int i = 0; i < 4; ++i) {
    if (running.input_shape[i] != next.input_shape[i]) {
      return Error(Errc::kInvalidArgument,
                   "reload: the new model takes %ux%ux%u input, the running one %ux%ux%u; "
                   "restart aprt to change the input",
                   unsigned(next.input_shape[1]), unsigned(next.input_shape[2]),
                   unsigned(next.input_shape[3]), unsigned(running.input_shape[1]),
                   unsigned(running.input_shape[2]), unsigned(running.input_shape[3]));
    }
  }
  if (running.norm_channels != next.norm_channels) {
    return Error(Errc::kInvalidArgument, "reload: the new model normalises %d channels, not %d",
                 next.norm_channels, running.norm_channels);
  }
  for (int c = 0; c < running.norm_channels; ++c) {
    if (running.norm_mean[c] != next.norm_mean[c] || running.norm_std[c] != next.norm_std[c]) {
      return Error(Errc::kInvalidArgument,
                   "reload: the new model normalises its input differently (channel %d mean/std); "
                   "restart aprt to change the preprocessing",
                   c);
    }
  }
  return ok();
}

}  // namespace aprt
