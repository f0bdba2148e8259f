// A fixed-length FIFO that hands values out a set number of pushes late.
//
// DelayLine<T> d(3, zero); d.Push(v) returns the value pushed 3 calls earlier (or
// `zero` while the line is filling). Length 0 returns v itself. It is a plain value:
// copying it copies the values in flight, so a copied simulation state replays exactly.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <vector>

namespace twinsim {

template <typename T>
class DelayLine {
 public:
  DelayLine() = default;
  DelayLine(int length, const T& fill) : buffer_(static_cast<std::size_t>(length), fill) {
    if (length < 0) throw std::invalid_argument("DelayLine: negative length");
  }

  int length() const { return static_cast<int>(buffer_.size()); }

  // Pushes `value` in and returns the value that entered `length()` pushes ago.
  T Push(const T& value) {
    if (buffer_.empty()) return value;
    T out = buffer_[head_];
    buffer_[head_] = value;
    head_ = (head_ + 1) % buffer_.size();
    return out;
  }

  // As Push, with the value out written into *out: assignments only, so a T that
  // holds storage (a vector) is not allocated again when *out already has its size.
  void Push(const T& value, T* out) {
    if (buffer_.empty()) {
      *out = value;
      return;
    }
    *out = buffer_[head_];
    buffer_[head_] = value;
    head_ = (head_ + 1) % buffer_.size();
  }

  // The value Push() will return next, without pushing.
  const T& Front() const { return buffer_[head_]; }

  // Sets every value in flight to `value` (e.g. the commands already sent before t0).
  void Fill(const T& value) {
    for (auto& b : buffer_) b = value;
    head_ = 0;
  }

  // The values in flight, oldest first.
  std::vector<T> InFlight() const {
    std::vector<T> out;
    out.reserve(buffer_.size());
    for (std::size_t i = 0; i < buffer_.size(); ++i) out.push_back(buffer_[(head_ + i) % buffer_.size()]);
    return out;
  }

 private:
  std::vector<T> buffer_;
  std::size_t head_ = 0;
};

}  // namespace twinsim
