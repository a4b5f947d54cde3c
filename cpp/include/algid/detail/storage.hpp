#pragma once
/// @file storage.hpp
/// Storage whose size is a template parameter where firmware needs it and a run-time value
/// elsewhere: `Storage<T, Size>` is a std::array for Size >= 0 and, for Size == Dynamic, a heap
/// buffer sized once in the configuration phase (`resize()`) and never again. Both index the
/// same way, so the estimators that hold them have one implementation for both.

#include "algid/types.hpp"

#include <array>
#include <cstddef>
#include <memory>

namespace algid {
namespace detail {

/// Size (or count) `n` of a Storage: the compile-time Size when it has one.
template <int Size>
constexpr int fixed_or(int n) noexcept {
  return Size == Dynamic ? n : Size;
}

/// Size elements of T, or a run-time number of them (Size == Dynamic).
template <class T, int Size>
class Storage {
 public:
  /// Fixed storage: `n` must equal Size (checked by the owner's configuration).
  void resize(int) noexcept {}
  T& operator[](int i) noexcept { return data_[static_cast<std::size_t>(i)]; }
  const T& operator[](int i) const noexcept { return data_[static_cast<std::size_t>(i)]; }
  T* data() noexcept { return data_.data(); }
  const T* data() const noexcept { return data_.data(); }
  int size() const noexcept { return Size; }
  void fill(const T& value) noexcept { data_.fill(value); }

 private:
  std::array<T, static_cast<std::size_t>(Size > 0 ? Size : 1)> data_{};
};

/// Run-time sized: allocated by resize() (configuration phase only), aligned for the SIMD
/// registers it holds (C++17 aligned new).
template <class T>
class Storage<T, Dynamic> {
 public:
  Storage() = default;
  Storage(const Storage& other) : Storage() { *this = other; }
  Storage(Storage&&) noexcept = default;
  Storage& operator=(const Storage& other) {
    if (this != &other) {
      resize(other.size_);
      for (int i = 0; i < size_; ++i) data_[static_cast<std::size_t>(i)] = other[i];
    }
    return *this;
  }
  Storage& operator=(Storage&&) noexcept = default;

  /// Allocate `n` value-initialised elements. May be called in the configuration phase only.
  void resize(int n) {
    data_.reset(n > 0 ? new T[static_cast<std::size_t>(n)]() : nullptr);
    size_ = n > 0 ? n : 0;
  }
  T& operator[](int i) noexcept { return data_[static_cast<std::size_t>(i)]; }
  const T& operator[](int i) const noexcept { return data_[static_cast<std::size_t>(i)]; }
  T* data() noexcept { return data_.get(); }
  const T* data() const noexcept { return data_.get(); }
  int size() const noexcept { return size_; }
  void fill(const T& value) noexcept {
    for (int i = 0; i < size_; ++i) data_[static_cast<std::size_t>(i)] = value;
  }

 private:
  std::unique_ptr<T[]> data_;
  int size_ = 0;
};

}  // namespace detail
}  // namespace algid
