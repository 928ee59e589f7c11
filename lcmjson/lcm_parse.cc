/// Parsing .lcm files (the LCM type language) and lcm-gen's fingerprint of a parsed struct.

#include <cctype>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "lcmjson/lcm_json.h"

namespace nimble::lcmjson {

namespace {

bool is_primitive(const std::string& type) {
  static const char* const kPrimitives[] = {"int8_t",  "int16_t", "int32_t", "int64_t", "byte",
                                            "boolean", "float",   "double",  "string"};
  for (const char* p : kPrimitives) {
    if (type == p) return true;
  }
  return false;
}

bool is_integer(const std::string& type) {
  return type == "int8_t" || type == "int16_t" || type == "int32_t" || type == "int64_t" || type == "byte";
}

/// One token: an identifier or number, a punctuation character, or a `///` comment block.
struct Token {
  enum Kind { kWord, kPunct, kDoc, kEnd } kind = kEnd;
  std::string text;
  int line = 0;
};

class Lexer {
 public:
  Lexer(const std::string& text, const std::string& file) : text_(text), file_(file) {}

  Token next() {
    std::string doc;
    int doc_line = 0;
    for (;;) {
      skip_space();
      if (pos_ >= text_.size()) return Token{Token::kEnd, "", line_};
      if (text_.compare(pos_, 3, "///") == 0) {
        // Consecutive /// lines form one doc comment, joined by a space.
        const std::size_t eol = text_.find('\n', pos_);
        std::string line = text_.substr(pos_ + 3, (eol == std::string::npos ? text_.size() : eol) - pos_ - 3);
        trim(&line);
        if (doc.empty()) doc_line = line_;
        if (!line.empty()) doc += (doc.empty() ? "" : " ") + line;
        pos_ = eol == std::string::npos ? text_.size() : eol;
        continue;
      }
      if (text_.compare(pos_, 2, "//") == 0) {
        const std::size_t eol = text_.find('\n', pos_);
        pos_ = eol == std::string::npos ? text_.size() : eol;
        continue;
      }
      if (text_.compare(pos_, 2, "/*") == 0) {
        const std::size_t end = text_.find("*/", pos_ + 2);
        if (end == std::string::npos) fail("a /* comment that does not end");
        for (std::size_t i = pos_; i < end; ++i) line_ += text_[i] == '\n';
        pos_ = end + 2;
        continue;
      }
      break;
    }
    if (!doc.empty()) {
      return Token{Token::kDoc, doc, doc_line};
    }
    const char c = text_[pos_];
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.' || c == '+') {
      const std::size_t start = pos_;
      while (pos_ < text_.size()) {
        const char d = text_[pos_];
        if (!(std::isalnum(static_cast<unsigned char>(d)) || d == '_' || d == '.' || d == '-' || d == '+')) break;
        ++pos_;
      }
      return Token{Token::kWord, text_.substr(start, pos_ - start), line_};
    }
    ++pos_;
    return Token{Token::kPunct, std::string(1, c), line_};
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(file_ + ":" + std::to_string(line_) + ": " + what);
  }

 private:
  void skip_space() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }
  static void trim(std::string* s) {
    while (!s->empty() && std::isspace(static_cast<unsigned char>(s->back()))) s->pop_back();
    std::size_t i = 0;
    while (i < s->size() && std::isspace(static_cast<unsigned char>((*s)[i]))) ++i;
    s->erase(0, i);
  }

  const std::string& text_;
  const std::string& file_;
  std::size_t pos_ = 0;
  int line_ = 1;
};

class Parser {
 public:
  Parser(const std::string& text, const std::string& file) : lexer_(text, file), file_(file), text_(text) { advance(); }

  std::vector<LcmStruct> parse() {
    std::vector<LcmStruct> out;
    std::string package;
    while (tok_.kind != Token::kEnd) {
      const std::string doc = take_doc();
      if (tok_.kind == Token::kEnd) break;
      const std::string word = expect_word("'package' or 'struct'");
      if (word == "package") {
        package = expect_word("a package name");
        expect(";");
      } else if (word == "struct") {
        out.push_back(parse_struct(package, doc));
      } else {
        lexer_.fail("expected 'package' or 'struct', found '" + word + "'");
      }
    }
    return out;
  }

 private:
  LcmStruct parse_struct(const std::string& package, const std::string& doc) {
    LcmStruct s;
    s.package = package;
    s.comment = doc;
    s.name = expect_word("a struct name");
    s.source = text_;
    s.file = file_;
    expect("{");
    for (;;) {
      const std::string field_doc = take_doc();
      if (tok_.kind == Token::kPunct && tok_.text == "}") {
        advance();
        break;
      }
      const std::string first = expect_word("a field type, 'const' or '}'");
      if (first == "const") {
        const std::string type = expect_word("a constant's type");
        if (!is_primitive(type) || type == "string") lexer_.fail("a constant of type '" + type + "'");
        for (;;) {
          LcmConst c;
          c.type = type;
          c.comment = field_doc;
          c.name = expect_word("a constant's name");
          expect("=");
          c.value = expect_word("a constant's value");
          s.consts.push_back(c);
          if (tok_.kind == Token::kPunct && tok_.text == ",") {
            advance();
            continue;
          }
          expect(";");
          break;
        }
        continue;
      }
      LcmField f;
      f.type = first;
      if (!is_primitive(f.type)) {
        lexer_.fail("field type '" + f.type + "' is not a primitive type (the rig's types nest no structs)");
      }
      f.name = expect_word("a field name");
      while (tok_.kind == Token::kPunct && tok_.text == "[") {
        advance();
        const std::string dim = expect_word("an array size");
        if (!std::isdigit(static_cast<unsigned char>(dim[0]))) {
          bool found = false;
          for (const auto& earlier : s.fields) {
            if (earlier.name == dim && earlier.dims.empty() && is_integer(earlier.type) && earlier.type != "byte")
              found = true;
          }
          if (!found) lexer_.fail("array size '" + dim + "' is not an earlier integer field of " + s.name);
        } else {
          for (char c : dim) {
            if (!std::isdigit(static_cast<unsigned char>(c))) lexer_.fail("array size '" + dim + "' is not a number");
          }
        }
        f.dims.push_back(dim);
        expect("]");
      }
      expect(";");
      f.comment = field_doc;
      const std::size_t close = f.comment.rfind(']');
      const std::size_t open = close == std::string::npos ? std::string::npos : f.comment.rfind('[', close);
      if (open != std::string::npos) f.unit = f.comment.substr(open + 1, close - open - 1);
      for (const auto& earlier : s.fields) {
        if (earlier.name == f.name) lexer_.fail("field '" + f.name + "' declared twice in " + s.name);
      }
      s.fields.push_back(f);
    }
    s.fingerprint = lcm_fingerprint(s);
    s.rig_time_field = rig_time_field(s);
    return s;
  }

  static int rig_time_field(const LcmStruct& s) {
    auto index = [&s](const std::string& name) {
      for (std::size_t i = 0; i < s.fields.size(); ++i) {
        if (s.fields[i].name == name && s.fields[i].type == "int64_t" && s.fields[i].dims.empty())
          return static_cast<int>(i);
      }
      return -1;
    };
    const int utime = index("utime");
    if (utime >= 0) {
      const std::string& c = s.fields[static_cast<std::size_t>(utime)].comment;
      if (c.find("Wall-clock") == std::string::npos && c.find("wall clock") == std::string::npos) return utime;
    }
    return index("rig_utime");
  }

  /// lcm-gen's hash of a struct (lcmgen.c: member names, primitive type names, dimensions; not the
  /// struct's name), rotated left by one bit as the generated code does for a struct without
  /// nested types.
  static uint64_t lcm_fingerprint(const LcmStruct& s) {
    uint64_t v = 0x12345678;
    auto update = [&v](int c) {
      const uint64_t sign_shift = static_cast<uint64_t>(static_cast<int64_t>(v) >> 55);  // arithmetic, as lcm-gen
      v = ((v << 8) ^ sign_shift) + static_cast<uint64_t>(static_cast<int64_t>(static_cast<signed char>(c)));
    };
    auto update_string = [&update](const std::string& text) {
      update(static_cast<int>(text.size()));
      for (char c : text) update(c);
    };
    for (const auto& f : s.fields) {
      update_string(f.name);
      update_string(f.type);
      update(static_cast<int>(f.dims.size()));
      for (const auto& d : f.dims) {
        update(std::isdigit(static_cast<unsigned char>(d[0])) ? 0 : 1);  // LCM_CONST 0, LCM_VAR 1
        update_string(d);
      }
    }
    return (v << 1) + ((v >> 63) & 1);
  }

  std::string take_doc() {
    std::string doc;
    while (tok_.kind == Token::kDoc) {
      doc = tok_.text;  // the comment block right above what follows
      advance();
    }
    return doc;
  }
  void advance() { tok_ = lexer_.next(); }
  std::string expect_word(const std::string& what) {
    if (tok_.kind != Token::kWord) lexer_.fail("expected " + what + ", found '" + tok_.text + "'");
    std::string w = tok_.text;
    advance();
    return w;
  }
  void expect(const std::string& punct) {
    if (tok_.kind != Token::kPunct || tok_.text != punct) {
      lexer_.fail("expected '" + punct + "', found '" +
                  (tok_.kind == Token::kEnd ? std::string("end of file") : tok_.text) + "'");
    }
    advance();
  }

  Lexer lexer_;
  const std::string& file_;
  const std::string& text_;
  Token tok_;
};

}  // namespace

std::vector<LcmStruct> parse_lcm(const std::string& text, const std::string& file) {
  return Parser(text, file).parse();
}

}  // namespace nimble::lcmjson
