#pragma once
// A read-only std::istream over bytes in memory (C++23's std::ispanstream, for C++20): the
// stream-based readers (PLY, compressed PLY) read a file or a buffer through the same code.
// The bytes are not copied; they must outlive the stream. Seeks within the buffer succeed,
// seeks outside it fail (the stream's position is then unchanged), as for a file.
#include <cstdint>
#include <istream>
#include <span>
#include <streambuf>

namespace vcar::io::detail {

class ByteStreambuf : public std::streambuf {
public:
  explicit ByteStreambuf(std::span<const std::uint8_t> bytes) {
    char* b = const_cast<char*>(reinterpret_cast<const char*>(bytes.data()));
    setg(b, b, b + bytes.size());
  }

protected:
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override {
    if (!(which & std::ios_base::in)) return pos_type(off_type(-1));
    const off_type base = dir == std::ios_base::beg ? 0 : dir == std::ios_base::cur ? gptr() - eback() : egptr() - eback();
    const off_type to = base + off;
    if (to < 0 || to > egptr() - eback()) return pos_type(off_type(-1));
    setg(eback(), eback() + to, egptr());
    return pos_type(to);
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
    return seekoff(off_type(pos), std::ios_base::beg, which);
  }
};

class ByteStream : public std::istream {
public:
  explicit ByteStream(std::span<const std::uint8_t> bytes) : std::istream(nullptr), buf_(bytes) { rdbuf(&buf_); }

private:
  ByteStreambuf buf_;
};

}  // namespace vcar::io::detail
