// Expected<T>: a value or an Error. Status = Expected<void>.
//
// Deliberately small (no monadic chains): test it with a plain `if`.
//   auto model = ModelFile::parse(bytes);
//   if (!model) return model.error();
#pragma once

#include <new>
#include <type_traits>
#include <utility>

#include "runtime/base/error.h"

namespace aprt {

template <class T>
class [[nodiscard]] Expected {
 public:
  Expected(const T& value) : has_(true) { new (&value_) T(value); }           // NOLINT implicit
  Expected(T&& value) : has_(true) { new (&value_) T(std::move(value)); }     // NOLINT implicit
  Expected(const Error& error) : has_(false) { new (&error_) Error(error); }  // NOLINT implicit
  Expected(Expected&& other) noexcept : has_(other.has_) {
    if (has_) {
      new (&value_) T(std::move(other.value_));
    } else {
      new (&error_) Error(other.error_);
    }
  }
  Expected(const Expected&) = delete;
  Expected& operator=(const Expected&) = delete;
  Expected& operator=(Expected&&) = delete;
  ~Expected() {
    if (has_) value_.~T();
  }

  explicit operator bool() const noexcept { return has_; }
  bool has_value() const noexcept { return has_; }
  T& value() & { return value_; }
  const T& value() const& { return value_; }
  T&& value() && { return std::move(value_); }
  T& operator*() & { return value_; }
  T* operator->() { return &value_; }
  const T* operator->() const { return &value_; }
  const Error& error() const noexcept { return error_; }

 private:
  bool has_;
  union {
    T value_;
    Error error_;
  };
};

template <>
class [[nodiscard]] Expected<void> {
 public:
  Expected() noexcept = default;
  Expected(const Error& error) noexcept : error_(error) {}  // NOLINT implicit
  explicit operator bool() const noexcept { return error_.code() == Errc::kOk; }
  bool has_value() const noexcept { return error_.code() == Errc::kOk; }
  const Error& error() const noexcept { return error_; }

 private:
  Error error_;
};

using Status = Expected<void>;

inline Status ok() noexcept {
  return Status();
}

}  // namespace aprt
