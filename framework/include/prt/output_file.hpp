// Where a command may write, and how: every output is checked before any work
// starts (so a refusal loses nothing) and written through a temporary file
// beside it that is renamed into place only when complete.
#pragma once
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace prt {

// What a file holds, judged from its first bytes; a text file named *.toml
// counts as a scene, which only --force may replace.
// JSON (text starting with { or [) and CSV (a *.csv text) are kinds of their
// own, so a report replaces an earlier report, never a note.
enum class FileKind { missing, bake, png, exr, scene, text, json, csv, other };
const char* to_string(FileKind kind);
FileKind detect_file_kind(const std::filesystem::path& file);

// The kind of a text report named `file`: json, csv or plain text, by extension.
FileKind report_kind(const std::filesystem::path& file);

struct OutputRequest {
  std::filesystem::path path;
  FileKind kind = FileKind::other;       // what the command will write there
  std::string role = "output";           // e.g. "bake file", "image", for messages
  bool create_folder = false;            // a scene's default output folder may be made
  std::string force_option = "--force";  // how the caller says "overwrite", for messages
};

// Refuses, with one message naming the path, an output that is a directory,
// device, FIFO or socket; that lies in a missing folder (unless create_folder);
// that is the same file as any of `inputs`; or that holds a file of another
// kind than the one to be written (unless `force`). Missing inputs are ignored.
void check_output(const OutputRequest& output, const std::vector<std::filesystem::path>& inputs,
                  bool force = false);

// Writes through a temporary ".NAME.tmp-PID-N" created with O_EXCL in the
// output's folder and renames it into place only after `write` returns. The
// temporary is removed on an exception and on SIGINT/SIGTERM; temporaries of
// processes that no longer exist are removed by the next write to the folder.
void write_atomically(const std::filesystem::path& file,
                      const std::function<void(const std::filesystem::path&)>& write);

// Writes `text` to `file` through write_atomically.
void write_text_file(const std::filesystem::path& file, const std::string& text);

// Writes `bytes` to the new file `path` with every write, fsync and close
// checked; a failure throws "FILE: no space left on device while writing"
// (FILE is `shown`, the name the user knows, when given).
void write_bytes_checked(const std::filesystem::path& path, const void* bytes, std::size_t size,
                         const std::filesystem::path& shown = {});

// Writes all `size` bytes to `descriptor`, retrying short writes and EINTR:
// 0 when done, otherwise the errno of the failure (ENOSPC for a write that
// wrote nothing). The one write loop of every checked writer.
int write_fully(int descriptor, const void* bytes, std::size_t size);

// Syncs a folder after a rename into it (best effort: the renamed file is
// whole either way; the sync makes the rename durable).
void sync_folder(const std::filesystem::path& folder);

// Flushes a written file to the device (fsync), checked: write errors that the
// page cache deferred (a full disk, a failing device) surface here.
void flush_to_device(const std::filesystem::path& path, const std::filesystem::path& shown = {});

// "FILE: no space left on device while writing": one located message for a
// failed system call on a file, from errno's value.
std::string io_failure(const std::filesystem::path& file, int error_number, const char* doing);

}  // namespace prt
