#pragma once
/// \file
/// Optional diagnostics sink. The library never prints; it hands messages to a
/// user-supplied callback, which may be empty.

#include <functional>
#include <string_view>

namespace semlio {

/// Severity of a diagnostic message.
enum class LogLevel { kDebug, kInfo, kWarning };

/// A callable that receives diagnostics; an empty Logger drops them.
using Logger = std::function<void(LogLevel, std::string_view)>;

/// Sends a message to the logger when one is set.
inline void log(const Logger& logger, LogLevel level, std::string_view message) {
  if (logger) logger(level, message);
}

}  // namespace semlio
