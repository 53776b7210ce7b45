// Every file pathcl writes (images, checkpoints, statistics, hit files, cached kernel binaries) is
// written to a temporary file beside its target and renamed over it, so no reader, crash or interrupt
// ever sees half a file. While a temporary file exists it is registered, so that a process ended at
// once by a signal (runtime/interrupt.h) can remove it first.
#pragma once
#include <functional>
#include <string>

// Calls write(tmp), which writes the whole file at tmp and throws on failure, then renames tmp to
// path. On any failure tmp is removed and RuntimeFailure("PATH: cannot write[ WHAT]: REASON") is
// thrown; `what` names the kind of file ("the EXR file").
void write_file_atomically(const std::string& path, const std::string& what,
                           const std::function<void(const std::string& tmp)>& write);
void write_text_file(const std::string& path, const std::string& text);
void write_binary_file(const std::string& path, const void* data, size_t bytes);

// Removes the temporary files being written now. Async-signal-safe (only unlink(2)).
void remove_partial_files_now();
