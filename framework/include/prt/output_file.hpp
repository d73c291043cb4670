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
enum class FileKind { missing, bake, png, scene, text, other };
const char* to_string(FileKind kind);
FileKind detect_file_kind(const std::filesystem::path& file);

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

}  // namespace prt
