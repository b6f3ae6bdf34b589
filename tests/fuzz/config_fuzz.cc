// libFuzzer targets: arbitrary text as an aprt configuration (YAML) through
// the parser and every key's reader (config_fuzz, APRT_FUZZ_PARSER 1), and
// as a DBC file through the DBC parser (dbc_fuzz, 2). Refused with a message
// or accepted; never a crash, a stack overflow (nesting) or quadratic time
// (duplicate keys).
#include <cstdint>
#include <string>

#include "drivers/can/dbc.h"
#include "runtime/config/config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
#if APRT_FUZZ_PARSER == 1
  auto c = aprt::parse_config(text, "fuzz.yaml");
  if (!c) (void)c.error().message();
#else
  auto d = aprt::can::parse_dbc(text, "fuzz.dbc");
  if (!d) (void)d.error().message();
#endif
  return 0;
}
