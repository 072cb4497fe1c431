// vds encoder: the PLY check (mesh_ply_check.h).
#include "mesh_ply_check.h"

#include <cstring>
#include <stdexcept>
#include <vector>

namespace vds::enc {

namespace {

constexpr size_t kMaxHeaderBytes = 64 * 1024;
constexpr size_t kMaxElements = 64;
constexpr size_t kMaxProperties = 256;

enum class Format { ascii, binary_le, binary_be };

struct Property {
  std::string name;
  int size = 0;        // bytes of a scalar (binary), or of a list's items
  int count_size = 0;  // list: bytes of its count; 0 for a scalar
  bool count_signed = false;
  bool item_float = false, item_signed = false;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> props;
  size_t header_line = 0;
};

// Byte size of a PLY scalar type name (0: unknown).
int type_size(const std::string& t, bool* is_float, bool* is_signed) {
  struct T {
    const char* name;
    int size;
    bool f, s;
  };
  static const T kTypes[] = {{"char", 1, false, true},    {"int8", 1, false, true},     {"uchar", 1, false, false},
                             {"uint8", 1, false, false},  {"short", 2, false, true},    {"int16", 2, false, true},
                             {"ushort", 2, false, false}, {"uint16", 2, false, false},  {"int", 4, false, true},
                             {"int32", 4, false, true},   {"uint", 4, false, false},    {"uint32", 4, false, false},
                             {"float", 4, true, true},    {"float32", 4, true, true},   {"double", 8, true, true},
                             {"float64", 8, true, true}};
  for (const T& k : kTypes)
    if (t == k.name) {
      *is_float = k.f;
      *is_signed = k.s;
      return k.size;
    }
  return 0;
}

[[noreturn]] void fail(const std::string& name, const std::string& what) { throw std::runtime_error(name + ": " + what); }

std::vector<std::string> words(const std::string& line) {
  std::vector<std::string> w;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t s = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > s) w.push_back(line.substr(s, i - s));
  }
  return w;
}

// Text as it can be shown in one line of an error message.
std::string printable(const std::string& t) {
  std::string o;
  for (unsigned char c : t) o += c >= 0x20 && c < 0x7F ? static_cast<char>(c) : '?';
  return o;
}

bool digits(const std::string& t, size_t& i) {
  const size_t s = i;
  while (i < t.size() && t[i] >= '0' && t[i] <= '9') ++i;
  return i > s;
}

// [-]digits, at most 18 of them.
bool plain_integer(const std::string& t) {
  const size_t sign = t.size() > 0 && t[0] == '-' ? 1 : 0;
  size_t i = sign;
  return digits(t, i) && i == t.size() && t.size() - sign <= 18;
}

// [+-]digits[.digits][(e|E)[+-]digits], or [+-].digits...
bool plain_real(const std::string& t) {
  size_t i = t.size() > 0 && (t[0] == '-' || t[0] == '+') ? 1 : 0;
  const bool whole = digits(t, i);
  bool frac = false;
  if (i < t.size() && t[i] == '.') {
    ++i;
    frac = digits(t, i);
  }
  if (!whole && !frac) return false;
  if (i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
    ++i;
    if (i < t.size() && (t[i] == '-' || t[i] == '+')) ++i;
    if (!digits(t, i)) return false;
  }
  return i == t.size();
}

bool is_face(const Element& e) { return e.name == "face"; }
bool is_index_list(const Property& p) {
  return p.count_size != 0 && (p.name == "vertex_indices" || p.name == "vertex_index");
}

// The body's reader: binary (either byte order) or ASCII tokens; positions
// are reported as byte offsets or lines.
class Body {
 public:
  Body(const uint8_t* data, size_t size, size_t at, Format f, const std::string& name)
      : p_(data), size_(size), at_(at), f_(f), name_(name) {}

  std::string where() const {
    if (f_ != Format::ascii) return "byte " + std::to_string(at_);
    return "line " + std::to_string(line_);
  }
  size_t remaining() const { return size_ - at_; }

  // A scalar as a signed integer (floats truncated; only list counts and
  // indices are read as values). false at the end of the data.
  bool read(int size, bool is_float, bool is_signed, int64_t* v) {
    if (f_ == Format::ascii) return token(is_float, v);
    if (remaining() < static_cast<size_t>(size)) return false;
    uint64_t u = 0;
    for (int i = 0; i < size; ++i) {
      const uint64_t b = p_[at_ + (f_ == Format::binary_le ? i : size - 1 - i)];
      u |= b << (8 * i);
    }
    at_ += static_cast<size_t>(size);
    if (is_float) {
      *v = 0;  // values are not checked
      return true;
    }
    if (is_signed && size < 8 && (u >> (8 * size - 1)) != 0) u |= ~uint64_t{0} << (8 * size);
    *v = static_cast<int64_t>(u);
    return true;
  }

 private:
  // The next whitespace-separated token as a number.
  bool token(bool is_float, int64_t* v) {
    while (at_ < size_ && (p_[at_] == ' ' || p_[at_] == '\t' || p_[at_] == '\r' || p_[at_] == '\n')) {
      if (p_[at_] == '\n') ++line_;
      ++at_;
    }
    if (at_ >= size_) return false;
    const size_t s = at_;
    while (at_ < size_ && p_[at_] != ' ' && p_[at_] != '\t' && p_[at_] != '\r' && p_[at_] != '\n') ++at_;
    const std::string t(reinterpret_cast<const char*>(p_ + s), at_ - s);
    // Plain decimal only (no "nan", "inf", hexadecimal or a leading '+'
    // for integers), so that every reader of the file splits it alike.
    if (!(is_float ? plain_real(t) : plain_integer(t)))
      fail(name_, "'" + printable(t.substr(0, 32)) + "' is not " + (is_float ? "a number" : "an integer") + " (" +
                      where() + ")");
    *v = is_float ? 0 : std::strtoll(t.c_str(), nullptr, 10);
    return true;
  }

  const uint8_t* p_;
  size_t size_, at_;
  Format f_;
  const std::string& name_;
  size_t line_ = 0;

 public:
  void set_line(size_t l) { line_ = l; }
};

}  // namespace

bool looks_like_ply(const uint8_t* data, size_t size) {
  return size >= 4 && std::memcmp(data, "ply", 3) == 0 && (data[3] == '\n' || data[3] == '\r');
}

PlyCounts check_ply(const uint8_t* data, size_t size, const std::string& name) {
  if (!looks_like_ply(data, size)) fail(name, "not a PLY file (it must start with the line 'ply')");
  // --- Header ---
  std::vector<Element> elements;
  Format format = Format::ascii;
  bool have_format = false;
  size_t at = 0, line_no = 0;
  bool ended = false;
  while (!ended) {
    if (at >= size || at >= kMaxHeaderBytes)
      fail(name, at >= size ? "the header has no end_header line" : "the header is longer than 64 KiB");
    const uint8_t* nl = static_cast<const uint8_t*>(std::memchr(data + at, '\n', size - at));
    const size_t end = nl != nullptr ? static_cast<size_t>(nl - data) : size;
    std::string line(reinterpret_cast<const char*>(data + at), end - at);
    at = nl != nullptr ? end + 1 : size;
    ++line_no;
    // Lines end at '\n' (a '\r' before it is dropped): a lone '\r' would end
    // a line for another reader and hide what follows from this one.
    if (!line.empty() && line.back() == '\r') line.pop_back();
    for (unsigned char c : line)
      if ((c < 0x20 && c != '\t') || c == 0x7F)
        fail(name, "a control byte in the header (header line " + std::to_string(line_no) + ")");
    const std::vector<std::string> w = words(line);
    const std::string where = " (header line " + std::to_string(line_no) + ")";
    if (line_no == 1) {
      if (line != "ply") fail(name, "the first line is not 'ply'");
      continue;
    }
    if (w.empty()) continue;
    if (w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") {
      ended = true;
    } else if (w[0] == "format") {
      if (w.size() != 3 || w[2] != "1.0") fail(name, "unsupported format line '" + printable(line.substr(0, 64)) + "'" + where);
      if (w[1] == "ascii") format = Format::ascii;
      else if (w[1] == "binary_little_endian") format = Format::binary_le;
      else if (w[1] == "binary_big_endian") format = Format::binary_be;
      else fail(name, "unknown format '" + printable(w[1].substr(0, 32)) + "'" + where);
      have_format = true;
    } else if (w[0] == "element") {
      if (w.size() != 3) fail(name, "an element line needs a name and a count" + where);
      char* e = nullptr;
      const unsigned long long count = std::strtoull(w[2].c_str(), &e, 10);
      if (e == nullptr || *e != '\0' || w[2][0] == '-' || count > (uint64_t{1} << 32))
        fail(name, "element '" + printable(w[1].substr(0, 32)) + "' has a bad count '" + printable(w[2].substr(0, 32)) + "'" + where);
      if (elements.size() == kMaxElements) fail(name, "more than 64 elements" + where);
      for (const Element& e : elements)
        if (e.name == w[1]) fail(name, "a second element '" + printable(w[1].substr(0, 32)) + "'" + where);
      Element el;
      el.name = w[1];
      el.count = count;
      el.header_line = line_no;
      elements.push_back(el);
    } else if (w[0] == "property") {
      if (elements.empty()) fail(name, "a property before any element" + where);
      if (elements.back().props.size() == kMaxProperties) fail(name, "more than 256 properties in one element" + where);
      Property p;
      bool f = false, s = false;
      if (w.size() == 5 && w[1] == "list") {
        bool cf = false;
        p.count_size = type_size(w[2], &cf, &p.count_signed);
        p.size = type_size(w[3], &p.item_float, &p.item_signed);
        if (p.count_size == 0 || cf)
          fail(name, "a list count of type '" + printable(w[2].substr(0, 32)) + "' (an integer type is needed)" + where);
        if (p.size == 0) fail(name, "unknown type '" + printable(w[3].substr(0, 32)) + "'" + where);
        p.name = w[4];
      } else if (w.size() == 3) {
        p.size = type_size(w[1], &f, &s);
        if (p.size == 0) fail(name, "unknown type '" + printable(w[1].substr(0, 32)) + "'" + where);
        p.item_float = f;
        p.item_signed = s;
        p.name = w[2];
      } else {
        fail(name, "a property line needs a type and a name" + where);
      }
      elements.back().props.push_back(p);
    } else {
      fail(name, "unknown header keyword '" + printable(w[0].substr(0, 32)) + "'" + where);
    }
  }
  if (!have_format) fail(name, "the header has no format line");

  // --- The counts against the bytes the body can hold ---
  // Binary: every scalar and list count takes its bytes; ASCII: every value
  // takes at least a digit and a separator.
  const size_t body = size - at;
  uint64_t least = 0;
  uint64_t vertices = 0, faces = 0;
  bool have_vertex = false;
  for (const Element& e : elements) {
    uint64_t per = 0;
    for (const Property& p : e.props)
      per += format == Format::ascii ? 2 : static_cast<uint64_t>(p.count_size != 0 ? p.count_size : p.size);
    if (per == 0 && e.count > 0) fail(name, "element '" + e.name + "' has no properties but a count");
    const uint64_t bytes = per * e.count;  // < 2^32 * 256 * 8
    least += bytes;
    // (ASCII: the very last value needs no separator after it.)
    if (least > body + (format == Format::ascii ? 1 : 0))
      fail(name, "the header declares " + std::to_string(e.count) + " " + e.name + " elements (with those before, at least " +
                     std::to_string(least) + " bytes) but the file holds " + std::to_string(body) +
                     " bytes after its header (header line " + std::to_string(e.header_line) + ")");
    if (e.name == "vertex") {
      vertices = e.count;
      have_vertex = true;
    }
    if (is_face(e)) faces = e.count;
  }
  if (!have_vertex) fail(name, "no vertex element");

  // --- The body, walked once ---
  Body b(data, size, at, format, name);
  b.set_line(line_no + 1);
  for (const Element& e : elements) {
    for (uint64_t i = 0; i < e.count; ++i) {
      for (const Property& p : e.props) {
        const auto what_of = [&] { return e.name + " " + std::to_string(i) + " of " + std::to_string(e.count); };
        int64_t v = 0;
        if (p.count_size == 0) {
          if (!b.read(p.size, p.item_float, p.item_signed, &v))
            fail(name, "the file ends inside " + what_of() + " (" + b.where() + ")");
          continue;
        }
        int64_t n = 0;
        if (!b.read(p.count_size, false, p.count_signed, &n))
          fail(name, "the file ends inside " + what_of() + " (" + b.where() + ")");
        const bool indices = is_face(e) && is_index_list(p);
        if (n < 0 || (indices && (n < 3 || n > kPlyMaxFaceVertices)))
          fail(name, what_of() + " lists " + std::to_string(n) + " items" +
                         (indices ? " (a face needs 3 to " + std::to_string(kPlyMaxFaceVertices) + " vertices)" : "") +
                         " (" + b.where() + ")");
        if (format != Format::ascii && b.remaining() / static_cast<size_t>(p.size) < static_cast<uint64_t>(n))
          fail(name, what_of() + ": its list of " + std::to_string(n) + " items runs past the end of the file (" + b.where() + ")");
        for (int64_t k = 0; k < n; ++k) {
          if (!b.read(p.size, p.item_float, p.item_signed, &v))
            fail(name, "the file ends inside " + what_of() + " (" + b.where() + ")");
          if (indices && (p.item_float || v < 0 || static_cast<uint64_t>(v) >= vertices))
            fail(name, what_of() + ": vertex index " + std::to_string(v) + " is not one of the " + std::to_string(vertices) +
                           " vertices (" + b.where() + ")");
        }
      }
    }
  }
  return PlyCounts{vertices, faces};
}

}  // namespace vds::enc
