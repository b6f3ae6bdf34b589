// Loading the configured model for the loop, at start and on a reload:
// reads the file once, checks its signature when the configuration asks
// (model_signature.h) on exactly the bytes it then loads, and builds the
// engine with the configured options. A reload also checks that the new
// model fits the running pipeline (same input and normalisation: the
// preprocessing plan and the frame source stay as they are).
#pragma once

#include <memory>
#include <string>

#include "runtime/base/expected.h"
#include "runtime/config/config.h"
#include "runtime/engine/engine.h"

namespace aprt {

// What to load: the file, the engine's options, and the signature policy.
struct ModelRequest {
  std::string path;
  EngineOptions engine;
  std::string public_key;          // empty: signatures not checked
  bool require_signature = false;  // an unsigned model is refused
};

// The configured model (model, engine.*, model_signing.*).
ModelRequest model_request(const Config& config);

// The one way a model file becomes an engine: read once, its signature
// checked on exactly those bytes when the request has a key, loaded with
// the request's options. `note` receives a line for the log when a
// signature was checked or skipped.
Expected<std::unique_ptr<Engine>> load_model(const ModelRequest& request, std::string* note);

// ok() when `next` can replace `running` between two frames.
// A camera model needs a camera source, a LiDAR model a LiDAR one (the message
// names the source types that would fit).
// scans: what an opened source delivers (1 scans, 0 frames), -1: from its type
// (an mcap source passes until its file is open).
Status model_fits_source(const ModelMeta& m, const Config::Source& src, const std::string& model,
                         int scans = -1);

Status reload_compatible(const ModelMeta& running, const ModelMeta& next);

}  // namespace aprt
