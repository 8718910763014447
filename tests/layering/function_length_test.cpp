// Functions do one thing: no function of the library (src/) is longer than 120 lines, and none of
// the command line (apps/) longer than 80, counted from the first line of its signature to its
// closing brace (docs/design.md, "Rules the code follows": small functions). The functions that are longer today are listed below by file and name; the list only
// shrinks: a listed function that has come under the limit (or is gone) must leave the list, and
// an unlisted one over the limit fails the test. A banner comment inside a long function is where
// it wants to be cut.
//
// The scanner reads C++ as text, not as a compiler does: comments, string and character literals
// and preprocessor lines are blanked, then braces are matched; a brace opens a function when the
// text before it (since the last `;`, `{` or `}`) holds a `)` and the brace stands at namespace or
// class level. Lambdas inside a function count as part of it; a lambda at namespace level counts as
// a function of its own. The checker is tested on small snippets at the end of this file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

// A named namespace: the layering tests are one unity build, whose anonymous namespaces are one.
namespace function_length {

namespace fs = std::filesystem;

constexpr int kMaxFunctionLines = 120;

// A function of the command line (apps/) is shorter still: it should only read options, call the
// library and write what it returns.
constexpr int kMaxCommandLines = 80;

// The command-line functions over their limit today, listed and shrinking as kLongFunctionsToCut.
const std::set<std::string> kLongCommandsToCut = {};

// The functions over the limit today, as "path relative to the source root: name". Remove an
// entry when its function is cut below the limit; never add one (cut the function instead).
const std::set<std::string> kLongFunctionsToCut = {};

struct Function {
  std::string name;
  int first_line = 0;  // 1-based, the first line of its signature
  int lines = 0;
};

// `text` with comments, string and character literals and preprocessor lines replaced by spaces
// (newlines kept, so line numbers stay).
std::string blank_non_code(const std::string& text) {
  std::string out = text;
  std::size_t i = 0;
  const auto blank = [&](std::size_t from, std::size_t to) {
    for (std::size_t k = from; k < to && k < out.size(); ++k)
      if (out[k] != '\n') out[k] = ' ';
  };
  bool line_start = true;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n') {
      line_start = true;
      ++i;
      continue;
    }
    if (line_start && c == '#') {  // a preprocessor line, with its continuations
      std::size_t end = i;
      while (end < text.size() && !(text[end] == '\n' && text[end - 1] != '\\')) ++end;
      blank(i, end);
      i = end;
      continue;
    }
    if (c != ' ' && c != '\t') line_start = false;
    if (c == '/' && i + 1 < text.size() && text[i + 1] == '/') {
      const std::size_t end = text.find('\n', i);
      blank(i, end == std::string::npos ? text.size() : end);
      i = end == std::string::npos ? text.size() : end;
    } else if (c == '/' && i + 1 < text.size() && text[i + 1] == '*') {
      const std::size_t end = text.find("*/", i + 2);
      const std::size_t stop = end == std::string::npos ? text.size() : end + 2;
      blank(i, stop);
      i = stop;
    } else if (c == 'R' && i + 1 < text.size() && text[i + 1] == '"' &&
               (i == 0 || !(std::isalnum(static_cast<unsigned char>(text[i - 1])) || text[i - 1] == '_'))) {
      const std::size_t open = text.find('(', i + 2);
      if (open == std::string::npos) break;
      const std::string close = ")" + text.substr(i + 2, open - i - 2) + "\"";
      const std::size_t end = text.find(close, open);
      const std::size_t stop = end == std::string::npos ? text.size() : end + close.size();
      blank(i, stop);
      i = stop;
    } else if (c == '"' || (c == '\'' && !(i > 0 && std::isalnum(static_cast<unsigned char>(text[i - 1]))))) {
      // A character literal, unless the quote separates digits (1'000'000).
      std::size_t k = i + 1;
      while (k < text.size() && text[k] != c && text[k] != '\n') k += text[k] == '\\' ? 2 : 1;
      blank(i, k + 1);
      i = k + 1;
    } else {
      ++i;
    }
  }
  return out;
}

bool has_word(const std::string& text, const std::string& word) {
  for (std::size_t at = text.find(word); at != std::string::npos; at = text.find(word, at + 1)) {
    const bool before = at == 0 || !(std::isalnum(static_cast<unsigned char>(text[at - 1])) || text[at - 1] == '_');
    const std::size_t after = at + word.size();
    const bool behind =
        after >= text.size() || !(std::isalnum(static_cast<unsigned char>(text[after])) || text[after] == '_');
    if (before && behind) return true;
  }
  return false;
}

// The name of the function whose signature is `header`: the last identifier before its first
// parenthesis (`Type name(args)`, `Class::name(args)`, `auto name = [&](args)`).
std::string name_of(const std::string& header) {
  std::string before = header.substr(0, header.find('('));
  std::size_t end = before.size();
  while (end > 0 && !(std::isalnum(static_cast<unsigned char>(before[end - 1])) || before[end - 1] == '_')) --end;
  std::size_t start = end;
  while (start > 0 && (std::isalnum(static_cast<unsigned char>(before[start - 1])) || before[start - 1] == '_'))
    --start;
  std::string name = before.substr(start, end - start);
  // Qualified names keep their class: Loader::read rather than read.
  if (start >= 2 && before.compare(start - 2, 2, "::") == 0) {
    std::size_t q = start - 2;
    while (q > 0 && (std::isalnum(static_cast<unsigned char>(before[q - 1])) || before[q - 1] == '_')) --q;
    name = before.substr(q, start - q) + name;
  }
  return name.empty() ? "(unnamed)" : name;
}

// Whether a `{` after `header` opens a member initializer of a constructor (`S(int x) : a_{x}`):
// the header has a parameter list followed by a single colon, and the brace follows a name.
bool is_member_initializer(const std::string& header) {
  std::string trimmed = header;
  while (!trimmed.empty() && std::isspace(static_cast<unsigned char>(trimmed.back()))) trimmed.pop_back();
  if (trimmed.empty()) return false;
  const char last = trimmed.back();
  if (!(std::isalnum(static_cast<unsigned char>(last)) || last == '_' || last == '>')) return false;
  const std::size_t close = trimmed.find(')');
  if (close == std::string::npos) return false;
  for (std::size_t k = close; k < trimmed.size(); ++k) {
    if (trimmed[k] != ':') continue;
    if (k + 1 < trimmed.size() && trimmed[k + 1] == ':') {
      ++k;
      continue;
    }
    return true;
  }
  return false;
}

// The functions of one C++ source with their lengths.
std::vector<Function> find_functions(const std::string& source) {
  // scope: namespace, class, extern "C"; init: the braces of a member initializer (`: a_{x} {`)
  enum class Block { scope, function, other, init };
  const std::string code = blank_non_code(source);
  std::vector<Function> found;
  std::vector<Block> stack;
  std::vector<Function> open;  // the function being read (at most one: nested braces are Block::other)
  std::string header;
  int header_line = 0;
  int line = 1;
  for (const char c : code) {
    if (c == '\n') ++line;
    const bool in_function = std::find(stack.begin(), stack.end(), Block::function) != stack.end();
    if (c == '{') {
      Block kind = Block::other;
      if (!in_function && is_member_initializer(header)) {
        stack.push_back(Block::init);
        header += c;
        continue;
      }
      if (!in_function) {
        const bool is_scope = has_word(header, "namespace") || has_word(header, "class") ||
                              has_word(header, "struct") || has_word(header, "union") || has_word(header, "enum") ||
                              has_word(header, "extern");
        const bool has_call = header.find(')') != std::string::npos;
        std::string trimmed = header;
        while (!trimmed.empty() && std::isspace(static_cast<unsigned char>(trimmed.back()))) trimmed.pop_back();
        const bool initializer = !trimmed.empty() && (trimmed.back() == '=' || trimmed.back() == ',' ||
                                                      trimmed.back() == '(' || trimmed.back() == '{');
        if (has_call && !initializer && !(is_scope && header.find('(') == std::string::npos)) {
          kind = Block::function;
          open.push_back(Function{name_of(header), header_line, 0});
        } else if (is_scope || trimmed.empty()) {
          kind = is_scope ? Block::scope : Block::other;
        }
      }
      stack.push_back(kind);
      header.clear();
      header_line = 0;
    } else if (c == '}') {
      if (!stack.empty() && stack.back() == Block::init) {
        stack.pop_back();
        header += c;
        continue;
      }
      if (!stack.empty()) {
        if (stack.back() == Block::function && !open.empty()) {
          Function f = open.back();
          open.pop_back();
          f.lines = line - f.first_line + 1;
          found.push_back(f);
        }
        stack.pop_back();
      }
      header.clear();
      header_line = 0;
    } else if (c == ';') {
      header.clear();
      header_line = 0;
    } else {
      if (header_line == 0 && !std::isspace(static_cast<unsigned char>(c))) header_line = line;
      if (header_line != 0) header += c;
    }
  }
  return found;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

// "path: name" -> lines, for every function of the folder (src/, apps/) over the limit.
std::map<std::string, Function> long_functions(const fs::path& root, const char* folder, int limit) {
  std::map<std::string, Function> out;
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(root / folder)) {
    const std::string ext = entry.path().extension().string();
    if (entry.is_regular_file() && (ext == ".cpp" || ext == ".hpp" || ext == ".h" || ext == ".cc"))
      files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  for (const fs::path& file : files) {
    const std::string relative = fs::relative(file, root).generic_string();
    for (const Function& f : find_functions(read_text(file))) {
      if (f.lines <= limit) continue;
      std::string key = relative + ": " + f.name;
      // Two long functions of one name in one file (overloads) are told apart by a counter.
      for (int k = 2; out.count(key); ++k) key = relative + ": " + f.name + "#" + std::to_string(k);
      out[key] = f;
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// The real tree.

// The functions over `limit` that `allowed` does not list, and the listed ones no longer over it.
void check_ratchet(const char* folder, int limit, const std::set<std::string>& allowed, const char* list) {
  const std::map<std::string, Function> found = long_functions(NHDYN_SOURCE_DIR, folder, limit);
  std::ostringstream report;
  for (const auto& [key, f] : found) {
    if (allowed.count(key)) continue;
    report << "  " << key << " (line " << f.first_line << ", " << f.lines << " lines)\n";
  }
  EXPECT_TRUE(report.str().empty()) << "functions over " << limit
                                    << " lines; cut them where their banner comments are:\n"
                                    << report.str();
  std::ostringstream stale;
  for (const std::string& key : allowed)
    if (!found.count(key)) stale << "  \"" << key << "\",\n";
  EXPECT_TRUE(stale.str().empty()) << "these functions are no longer over " << limit
                                   << " lines (or are gone): remove them from " << list << ":\n"
                                   << stale.str();
}

TEST(FunctionLength, NoFunctionOfTheLibraryIsOverTheLimit) {
  check_ratchet("src", kMaxFunctionLines, kLongFunctionsToCut, "kLongFunctionsToCut");
}

// The command line is thin: each command's function reads its options, calls the library and
// writes what it returns, in at most 80 lines.
TEST(FunctionLength, NoFunctionOfTheCommandLineIsOverItsLimit) {
  check_ratchet("apps", kMaxCommandLines, kLongCommandsToCut, "kLongCommandsToCut");
}

// ---------------------------------------------------------------------------------------------
// The scanner on small snippets.

std::string body(int lines) {
  std::string out;
  for (int i = 0; i < lines; ++i) out += "  x += 1;\n";
  return out;
}

// "name@first_line+lines " for each function of `source`: a whole answer in one comparison.
std::string functions_of(const std::string& source) {
  std::string out;
  for (const Function& f : find_functions(source))
    out += f.name + "@" + std::to_string(f.first_line) + "+" + std::to_string(f.lines) + " ";
  return out;
}

TEST(FunctionLength, CountsFromSignatureToClosingBrace) {
  const std::string source = "namespace a {\nint f(int x,\n      int y) {\n" + body(5) + "}\n}  // namespace a\n";
  EXPECT_EQ(functions_of(source), "f@2+8 ");  // the two lines of the signature, 5 of body, the brace
}

TEST(FunctionLength, NestedBracesAndLambdasBelongToTheirFunction) {
  EXPECT_EQ(functions_of("void g() {\n  auto h = [&](int i) {\n    if (i) { return; }\n  };\n"
                         "  for (;;) {\n  }\n}\n"),
            "g@1+7 ");
}

TEST(FunctionLength, ClassMembersAreFunctionsAndInitializersAreNot) {
  EXPECT_EQ(functions_of("struct S : Base {\n  int m() const { return 1; }\n};\n"
                         "const std::array<int, 2> table = {1, 2};\nstd::vector<int> v{3};\n"
                         "int S::n(const char* s) {\n  return 0;\n}\n"
                         "S::S(int x) : a_{x}, b_(x) {\n  if (x) {\n    x = 0;\n  }\n}\n"),
            "m@2+1 S::n@6+3 S::S@9+5 ");
}

TEST(FunctionLength, BracesInCommentsStringsAndMacrosAreNotCode) {
  EXPECT_EQ(functions_of("// void x() {\n/* { */\n#define OPEN {\nconst char* s = \"{\";\nchar c = '}';\n"
                         "auto r = R\"js(function() { )js\";\nint f() {\n  return 1'000;\n}\n"),
            "f@7+3 ");
}

}  // namespace function_length
