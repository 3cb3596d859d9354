#pragma once
// vcar::Error: the one exception type of the library. It carries what is at fault (a file and
// byte offset, a view name, a parameter) separately from the message, so callers can report it.
#include <stdexcept>
#include <string>

namespace vcar {

class Error : public std::runtime_error {
public:
  explicit Error(const std::string& message, std::string where = {})
      : std::runtime_error(where.empty() ? message : where + ": " + message),
        where_(std::move(where)) {}
  // The file, view or parameter at fault ("" when the message says it all).
  const std::string& where() const noexcept { return where_; }

private:
  std::string where_;
};

}  // namespace vcar
