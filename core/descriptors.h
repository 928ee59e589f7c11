#pragma once
/// What a child process inherits: nothing but its standard streams. The rig's own descriptors
/// are opened close-on-exec where it opens them (OutputFile, the live view's sockets); what
/// libraries open without it (LCM's sockets) is closed in the child, between fork and exec.

namespace nimble {

/// Closes every descriptor from `first` on (close_range(2), or one by one where the kernel has
/// none). Async-signal-safe: for a child between fork and exec.
void close_descriptors_from(int first) noexcept;

/// Marks `fd` close-on-exec; false if it cannot be.
bool set_close_on_exec(int fd) noexcept;

}  // namespace nimble
