#include "drivers/input/lidar/scan_reader.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <new>

namespace aprt {
namespace {

// A whole decimal integer in [lo, hi], or false.
bool whole(const char* s, long lo, long hi, long* out) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(s, &end, 10);
  if (end == s || *end != '\0' || errno == ERANGE || v < lo || v > hi) return false;
  *out = v;
  return true;
}

bool ends_with(const char* s, const char* suffix) {
  const size_t a = std::strlen(s), b = std::strlen(suffix);
  return a >= b && std::strcmp(s + a - b, suffix) == 0;
}

// One PCD field: where it sits in a record and how to read it.
struct Field {
  int offset = -1;  // bytes into a binary record; column for ascii
  char type = 'F';
  int size = 4;
};

double field_value(const char* p, const Field& f) {
  switch (f.type) {
    case 'F':
      if (f.size == 8) {
        double d;
        std::memcpy(&d, p, 8);
        return d;
      } else {
        float v;
        std::memcpy(&v, p, 4);
        return v;
      }
    case 'U':
      if (f.size == 1) return double(uint8_t(p[0]));
      if (f.size == 2) {
        uint16_t v;
        std::memcpy(&v, p, 2);
        return v;
      } else {
        uint32_t v;
        std::memcpy(&v, p, 4);
        return v;
      }
    default:
      if (f.size == 1) return double(int8_t(p[0]));
      if (f.size == 2) {
        int16_t v;
        std::memcpy(&v, p, 2);
        return v;
      } else {
        int32_t v;
        std::memcpy(&v, p, 4);
        return v;
      }
  }
}

}  // namespace

Expected<std::unique_ptr<ScanReader>> ScanReader::create() {
  std::unique_ptr<ScanReader> r(new (std::nothrow) ScanReader());
  if (!r) return Error(Errc::kOutOfMemory, "lidar: out of memory");
  r->buf_ = static_cast<char*>(std::malloc(kBuffer + 1));
  if (!r->buf_) return Error(Errc::kOutOfMemory, "lidar: out of memory");
  return r;
}

ScanReader::~ScanReader() {
  std::free(buf_);
}

Status ScanReader::read(const char* path, const PointRegion& region, PointCloud* out) {
  out->clear(region);
  const bool pcd = ends_with(path, ".pcd");
  if (!pcd && !ends_with(path, ".bin")) {
    return Error(Errc::kUnsupported, "lidar: %s: neither .bin (KITTI) nor .pcd", path);
  }
  // A regular file of a bounded size: a FIFO or a device at the path (a scan
  // symlinked to /dev/zero) is refused, never read.
  auto f = open_input_file(path, kMaxScanBytes, "lidar scan");
  if (!f) return f.error();
  return pcd ? read_pcd(*f, path, out) : read_kitti(*f, path, out);
}

Status ScanReader::read_kitti(const InputFile& file, const char* path, PointCloud* out) {
  if (file.size() % 16 != 0) {
    return Error(Errc::kTruncated,
                 "lidar: %s: %llu bytes is not a whole number of 16-byte points (truncated?)", path,
                 static_cast<unsigned long long>(file.size()));
  }
  constexpr size_t chunk = kBuffer / 16 * 16;
  for (;;) {
    const long n = file.read(buf_, chunk);
    if (n < 0) return Error(Errc::kIo, "lidar: %s: %s", path, std::strerror(errno));
    for (long i = 0; i + 16 <= n; i += 16) {
      float p[4];
      std::memcpy(p, buf_ + i, 16);
      out->add(p[0], p[1], p[2], p[3]);
    }
    if (size_t(n) < chunk) break;
  }
  return ok();
}

Status ScanReader::read_pcd(const InputFile& file, const char* path, PointCloud* out) {
  // The header: lines up to and including DATA, at most one buffer long.
  const long got = file.read(buf_, kBuffer);
  if (got < 0) return Error(Errc::kIo, "lidar: %s: %s", path, std::strerror(errno));
  buf_[got] = '\0';
  constexpr int kMaxFields = 16;
  char names[kMaxFields][24] = {};
  char types[kMaxFields] = {};
  long sizes[kMaxFields] = {}, counts[kMaxFields] = {};
  int nfields = 0, ntypes = 0, nsizes = 0, ncounts = 0;
  bool too_many = false, bad_number = false;
  long points = -1;
  bool ascii = false, have_data = false;
  size_t pos = 0;
  while (pos < size_t(got) && !have_data) {
    char* line = buf_ + pos;
    char* nl = static_cast<char*>(std::memchr(line, '\n', size_t(got) - pos));
    if (!nl) return Error(Errc::kBadHeader, "lidar: %s: PCD header without DATA", path);
    *nl = '\0';
    pos = size_t(nl - buf_) + 1;
    char* save = nullptr;
    char* key = strtok_r(line, " \t\r", &save);
    if (!key || key[0] == '#') continue;
    auto each = [&](auto fn) {
      for (char* t = strtok_r(nullptr, " \t\r", &save); t; t = strtok_r(nullptr, " \t\r", &save)) {
        fn(t);
      }
    };
    if (!std::strcmp(key, "FIELDS")) {
      each([&](char* t) {
        if (nfields == kMaxFields) too_many = true;
        if (nfields < kMaxFields) std::snprintf(names[nfields++], sizeof names[0], "%s", t);
      });
    } else if (!std::strcmp(key, "SIZE")) {
      each([&](char* t) {
        if (nsizes == kMaxFields) too_many = true;
        if (nsizes < kMaxFields && !whole(t, 1, 8, &sizes[nsizes++])) bad_number = true;
      });
    } else if (!std::strcmp(key, "TYPE")) {
      each([&](char* t) {
        if (ntypes == kMaxFields) too_many = true;
        if (ntypes < kMaxFields) types[ntypes++] = t[1] == '\0' ? t[0] : '?';
      });
    } else if (!std::strcmp(key, "COUNT")) {
      each([&](char* t) {
        if (ncounts == kMaxFields) too_many = true;
        if (ncounts < kMaxFields && !whole(t, 1, kMaxCount, &counts[ncounts++])) bad_number = true;
      });
    } else if (!std::strcmp(key, "POINTS")) {
      char* t = strtok_r(nullptr, " \t\r", &save);
      if (!t || !whole(t, 0, kMaxPoints, &points)) bad_number = true;
    } else if (!std::strcmp(key, "DATA")) {
      char* t = strtok_r(nullptr, " \t\r", &save);
      if (!t || (std::strcmp(t, "ascii") && std::strcmp(t, "binary"))) {
        return Error(Errc::kUnsupported, "lidar: %s: PCD DATA %s is not supported (ascii, binary)",
                     path, t ? t : "(none)");
      }
      ascii = !std::strcmp(t, "ascii");
      have_data = true;
    }
  }
  if (!have_data) return Error(Errc::kBadHeader, "lidar: %s: PCD header without DATA", path);
  if (too_many) {
    return Error(Errc::kUnsupported, "lidar: %s: PCD with more than %d fields", path, kMaxFields);
  }
  if (bad_number) {
    return Error(Errc::kBadHeader,
                 "lidar: %s: PCD SIZE (1..8), COUNT (1..%ld) or POINTS (0..%ld) is not a whole "
                 "number in range",
                 path, kMaxCount, kMaxPoints);
  }
  if (nfields == 0 || nsizes != nfields || ntypes != nfields || points < 0) {
    return Error(Errc::kBadHeader,
                 "lidar: %s: PCD header inconsistent (%d FIELDS, %d SIZE, %d TYPE, POINTS %ld)",
                 path, nfields, nsizes, ntypes, points);
  }
  if (ncounts != 0 && ncounts != nfields) {
    return Error(Errc::kBadHeader, "lidar: %s: PCD header has %d COUNT values for %d FIELDS", path,
                 ncounts, nfields);
  }
  Field x, y, z, in;
  size_t offset = 0, column = 0;  // bounded: 16 fields x 8 bytes x kMaxCount
  for (int i = 0; i < nfields; ++i) {
    const long count = ncounts == nfields ? counts[i] : 1;
    const bool sized =
        (types[i] == 'F' && (sizes[i] == 4 || sizes[i] == 8)) ||
        ((types[i] == 'U' || types[i] == 'I') && (sizes[i] == 1 || sizes[i] == 2 || sizes[i] == 4));
    if (!sized || count < 1) {
      return Error(Errc::kBadHeader, "lidar: %s: PCD field %s has type %c size %ld count %ld", path,
                   names[i], types[i], sizes[i], count);
    }
    Field f{int(ascii ? column : offset), types[i], int(sizes[i])};
    if (!std::strcmp(names[i], "x")) x = f;
    if (!std::strcmp(names[i], "y")) y = f;
    if (!std::strcmp(names[i], "z")) z = f;
    if (!std::strcmp(names[i], "intensity")) in = f;
    offset += size_t(sizes[i]) * size_t(count);
    column += size_t(count);
  }
  if (x.offset < 0 || y.offset < 0 || z.offset < 0 || x.type != 'F' || y.type != 'F' ||
      z.type != 'F') {
    return Error(Errc::kBadHeader, "lidar: %s: PCD needs float fields x, y and z", path);
  }
  const size_t step = offset;
  if ((ascii && column > 16) || step > kBuffer / 2) {
    return Error(Errc::kUnsupported,
                 "lidar: %s: PCD records of %zu values / %zu bytes are too wide", path, column,
                 step);
  }
  // A binary body must hold what the header says, before any of it is read.
  if (!ascii && uint64_t(points) * step > file.size() - pos) {
    return Error(Errc::kTruncated,
                 "lidar: %s: PCD says %ld points of %zu bytes, the file holds %llu bytes after its "
                 "header (truncated?)",
                 path, points, step, static_cast<unsigned long long>(file.size() - pos));
  }
  // The data: what is left of the buffer, then more reads; a record or line
  // split across reads is carried to the buffer's start.
  size_t have = size_t(got) - pos;
  std::memmove(buf_, buf_ + pos, have);
  long done = 0;
  bool eof = size_t(got) < kBuffer;
  for (;;) {
    size_t used = 0;
    if (ascii) {
      buf_[have] = '\0';
      for (;;) {
        char* nl = static_cast<char*>(std::memchr(buf_ + used, '\n', have - used));
        if (!nl && !(eof && used < have)) break;
        char* end = nl ? nl : buf_ + have;
        *end = '\0';
        double v[16] = {};
        int col = 0;
        char* p = buf_ + used;
        while (col < 16) {
          char* next = nullptr;
          const double d = std::strtod(p, &next);
          if (next == p) break;
          v[col++] = d;
          p = next;
        }
        used = size_t(end - buf_) + (nl ? 1 : 0);
        if (col == 0) continue;  // a blank line
        if (done < points) {
          out->add(float(v[x.offset]), float(v[y.offset]), float(v[z.offset]),
                   in.offset >= 0 ? float(v[in.offset]) : 0.0f);
        }
        ++done;
        if (!nl) break;
      }
    } else {
      for (; used + step <= have && done < points; used += step, ++done) {
        const char* r = buf_ + used;
        out->add(float(field_value(r + x.offset, x)), float(field_value(r + y.offset, y)),
                 float(field_value(r + z.offset, z)),
                 in.offset >= 0 ? float(field_value(r + in.offset, in)) : 0.0f);
      }
    }
    std::memmove(buf_, buf_ + used, have - used);
    have -= used;
    if (eof || done >= points) break;
    if (have == kBuffer) {
      return Error(Errc::kBadHeader, "lidar: %s: a PCD line longer than %zu bytes", path, kBuffer);
    }
    const size_t want = kBuffer - have;
    const long n = file.read(buf_ + have, want);
    if (n < 0) return Error(Errc::kIo, "lidar: %s: %s", path, std::strerror(errno));
    have += size_t(n);
    eof = size_t(n) < want;
  }
  if (done != points) {
    return Error(Errc::kTruncated,
                 "lidar: %s: PCD says %ld points, the file holds %ld (truncated?)", path, points,
                 done);
  }
  return ok();
}

}  // namespace aprt
