// toml++ 3.3 has undefined behaviour on non-ASCII text: its whitespace test
// reaches __builtin_unreachable for most non-ASCII code points (e.g. U+00E9,
// U+FCFF), and it may test any character of a malformed value. So toml++ is
// handed ASCII only, with the same meaning: non-ASCII characters in basic
// strings become \u escapes, literal strings holding them become basic
// strings, comments lose them, and anywhere else they are refused (TOML's keys
// and bare values are ASCII). The text is also checked to be valid UTF-8
// without control characters, brackets to pair up and table headers to start
// with a key (toml++ assumes both). Errors say where, in the original text.
#include "scene_ascii.hpp"

#include <cctype>
#include <cstdint>
#include <cstdio>

#include "prt/error.hpp"

namespace prt {
namespace {

class AsciiScene {
 public:
  AsciiScene(const std::string& text, const std::filesystem::path& file)
      : text_(text), file_(file) {
    out_.reserve(text.size());
  }

  std::string convert() {
    for (std::size_t i = 0; i < text_.size();) {
      const auto c = static_cast<unsigned char>(text_[i]);
      if (c >= 0x80) {
        i += non_ascii(i, c);
        continue;
      }
      if ((c < 0x20 && c != '\t' && c != '\r' && c != '\n') || c == 0x7f)
        fail("control character 0x" + std::string(1, "0123456789abcdef"[c >> 4]) +
             std::string(1, "0123456789abcdef"[c & 15]) + "; a scene is UTF-8 text");
      const bool in_literal =
          context_ == Context::literal || context_ == Context::multiline_literal;
      const std::size_t step = next_context(i, c);
      copy(i, c, step, in_literal);
      advance(c, step);
      i += step;
    }
    return out_;
  }

 private:
  enum class Context { code, comment, basic, literal, multiline_basic, multiline_literal };

  [[noreturn]] void fail(const std::string& what) const {
    throw Error(SourceLocation{file_.string(), line_, column_}, what);
  }
  bool starts(std::size_t i, const char* token) const { return text_.compare(i, 3, token) == 0; }

  // A UTF-8 sequence at i (lead byte c): checked, then escaped (strings),
  // replaced (comments) or refused (code). Returns its length.
  std::size_t non_ascii(std::size_t i, unsigned char c) {
    const std::uint32_t code = decode_utf8(i, c);
    const std::size_t length = c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : 2;
    if (context_ == Context::code)
      fail("non-ASCII character outside a string or comment (keys and values are ASCII; quote it)");
    if (after_backslash_) fail("invalid escape sequence in a string");
    if ((context_ == Context::literal || context_ == Context::multiline_literal) &&
        !literal_rewritten_)
      rewrite_literal();
    if (context_ == Context::comment) {
      out_ += '?';
    } else {
      char escape[12];
      std::snprintf(escape, sizeof escape, code > 0xffff ? "\\U%08X" : "\\u%04X",
                    static_cast<unsigned>(code));
      out_ += escape;
    }
    at_line_start_ = false;
    ++column_;
    return length;
  }

  std::uint32_t decode_utf8(std::size_t i, unsigned char c) const {
    const int length = c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : c >= 0xc0 ? 2 : 0;
    if (length == 0 || c > 0xf4 || c == 0xc0 || c == 0xc1 || i + length > text_.size())
      fail("invalid UTF-8 byte; a scene is UTF-8 text");
    std::uint32_t code = c & (0xff >> (length + 1));
    for (int k = 1; k < length; ++k) {
      const auto next = static_cast<unsigned char>(text_[i + k]);
      if ((next & 0xc0) != 0x80) fail("invalid UTF-8 sequence; a scene is UTF-8 text");
      code = (code << 6) | (next & 0x3f);
    }
    const std::uint32_t smallest[5] = {0, 0, 0x80, 0x800, 0x10000};
    if (code < smallest[length] || code > 0x10ffff || (code >= 0xd800 && code <= 0xdfff))
      fail("invalid UTF-8 sequence; a scene is UTF-8 text");
    return code;
  }

  // A literal string is copied as is, unless it holds a non-ASCII character:
  // then it is rewritten as a basic string from its opening quote.
  void rewrite_literal() {
    const bool multiline = context_ == Context::multiline_literal;
    const std::string body = out_.substr(literal_start_ + (multiline ? 3 : 1));
    out_.resize(literal_start_);
    out_ += multiline ? "\"\"\"" : "\"";
    for (char ch : body) {
      if (ch == '\\' || ch == '"') out_ += '\\';
      out_ += ch;
    }
    literal_rewritten_ = true;
  }

  void require_table_key(std::size_t i) const {
    std::size_t k = i + 1;
    if (k < text_.size() && text_[k] == '[') ++k;
    while (k < text_.size() && (text_[k] == ' ' || text_[k] == '\t')) ++k;
    const char next = k < text_.size() ? text_[k] : '\n';
    if (!(std::isalnum(static_cast<unsigned char>(next)) || next == '_' || next == '-' ||
          next == '"' || next == '\'' || next == ']'))
      fail("a table header must start with a key, e.g. [mesh]");
  }

  // The context after the ASCII character c at i; returns how many
  // characters it takes (3 for a triple quote).
  std::size_t next_context(std::size_t i, unsigned char c) {
    switch (context_) {
      case Context::code:
        return in_code(i, c);
      case Context::basic:
      case Context::multiline_basic:
        if (after_backslash_) {
          after_backslash_ = false;
        } else if (c == '\\') {
          after_backslash_ = true;
        } else if (context_ == Context::basic && c == '"') {
          context_ = Context::code;
        } else if (context_ == Context::multiline_basic && starts(i, "\"\"\"")) {
          context_ = Context::code;
          return 3;
        }
        return 1;
      case Context::literal:
        if (c == '\'') context_ = Context::code;
        return 1;
      case Context::multiline_literal:
        if (!starts(i, "'''")) return 1;
        context_ = Context::code;
        return 3;
      case Context::comment:
        return 1;
    }
    return 1;
  }

  std::size_t in_code(std::size_t i, unsigned char c) {
    // Brackets must pair up: toml++ assumes a ']' or '}' closes what it opened.
    if (c == '[') {
      if (brackets_.empty() && at_line_start_) require_table_key(i);
      brackets_.push_back('[');
    }
    if (c == '{') brackets_.push_back('{');
    if (c == ']' || c == '}') {
      if (brackets_.empty() || brackets_.back() != (c == ']' ? '[' : '{'))
        fail(std::string("unmatched '") + char(c) + "'");
      brackets_.pop_back();
    }
    if (c == '#') context_ = Context::comment;
    if (c == '"') {
      const bool three = starts(i, "\"\"\"");
      context_ = three ? Context::multiline_basic : Context::basic;
      return three ? 3 : 1;
    }
    if (c == '\'') {
      const bool three = starts(i, "'''");
      literal_start_ = out_.size(), literal_rewritten_ = false;
      context_ = three ? Context::multiline_literal : Context::literal;
      return three ? 3 : 1;
    }
    return 1;
  }

  // Inside a rewritten literal, quotes and backslashes are escaped and the
  // closing quotes become double quotes; anything else is copied.
  void copy(std::size_t i, unsigned char c, std::size_t step, bool in_literal) {
    if (!(in_literal && literal_rewritten_)) {
      out_.append(text_, i, step);
    } else if (context_ == Context::code) {
      out_ += step == 3 ? "\"\"\"" : "\"";
    } else {
      if (c == '\\' || c == '"') out_ += '\\';
      out_ += static_cast<char>(c);
    }
  }

  void advance(unsigned char c, std::size_t step) {
    if (c == '\n') {
      if (context_ == Context::comment || context_ == Context::basic ||
          context_ == Context::literal)
        context_ = Context::code;  // single-line contexts end with the line
      ++line_, column_ = 1, at_line_start_ = true, after_backslash_ = false;
    } else {
      if (c != ' ' && c != '\t' && c != '\r') at_line_start_ = false;
      column_ += static_cast<int>(step);
    }
  }

  const std::string& text_;
  const std::filesystem::path& file_;
  std::string out_;
  Context context_ = Context::code;
  int line_ = 1, column_ = 1;
  std::size_t literal_start_ = 0;
  bool literal_rewritten_ = false, after_backslash_ = false, at_line_start_ = true;
  std::string brackets_;  // the '[' and '{' open in code
};

}  // namespace

std::string ascii_scene_text(const std::string& text, const std::filesystem::path& file) {
  return AsciiScene(text, file).convert();
}

}  // namespace prt
