// libFuzzer target: arbitrary bytes as a replay frame (PNG or JPEG, by
// content) through the image decoder, as the replay source reads them: a
// probe of the header, then the decode into a 640x480 slot. It must refuse
// or decode, never crash, overrun the slot or allocate without bound. An
// input that starts with 'M' goes, without that byte, through the in-memory
// JPEG path instead (MJPEG cameras).
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "drivers/codec/image_decoder.h"
#include "tests/fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static aprt::ImageDecoder* dec = aprt::ImageDecoder::create(size_t(1) << 20).value().release();
  static std::vector<uint8_t> slot(640 * 480 * 3);
  if (size > 0 && data[0] == 'M') {
    auto m = dec->decode_jpeg_memory(data + 1, size - 1, slot.data(), slot.size(), "fuzz");
    if (m && m->bytes > slot.size()) std::abort();
    return 0;
  }
  const char* path = aprt::fuzz::write_input(data, size, ".img");
  if (!path) return 0;
  auto probe = dec->probe(path);
  if (!probe) return 0;
  auto img = dec->decode(path, slot.data(), slot.size());
  if (img && (img->bytes > slot.size() || img->width != probe->width)) std::abort();
  return 0;
}
