// vds encoder: the Collada check (mesh_collada_check.h).
#include "mesh_collada_check.h"

#include <cstdlib>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <tinyxml2.h>

namespace vds::enc {
namespace {

using tinyxml2::XMLElement;

constexpr uint64_t kMaxCount = uint64_t{1} << 24;

[[noreturn]] void fail(const std::string& name, const std::string& what, const XMLElement* at) {
  throw std::runtime_error(name + ": " + what + (at ? " (line " + std::to_string(at->GetLineNum()) + ")" : ""));
}

// The whitespace-separated tokens of an element's text.
std::vector<std::string> tokens(const XMLElement* e) {
  std::vector<std::string> out;
  const char* t = e->GetText();
  if (t == nullptr) return out;
  const char* p = t;
  while (*p != '\0') {
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r') ++p;
    if (*p == '\0') break;
    const char* s = p;
    while (*p != '\0' && *p != ' ' && *p != '\t' && *p != '\n' && *p != '\r') ++p;
    out.emplace_back(s, p);
  }
  return out;
}

// A non-negative integer attribute (absent: `fallback`); refused if not digits or above kMaxCount.
uint64_t count_attr(const XMLElement* e, const char* attr, uint64_t fallback, const std::string& name) {
  const char* v = e->Attribute(attr);
  if (v == nullptr) return fallback;
  if (*v == '\0' || std::strlen(v) > 9 || std::strspn(v, "0123456789") != std::strlen(v))
    fail(name, std::string("<") + e->Name() + "> " + attr + "=\"" + v + "\" is not a count", e);
  const uint64_t n = std::strtoull(v, nullptr, 10);
  if (n > kMaxCount) fail(name, std::string("<") + e->Name() + "> " + attr + "=" + v + " (at most 16777216)", e);
  return n;
}

uint64_t index_of(const std::string& tok, const XMLElement* at, const std::string& name) {
  if (tok.empty() || tok.size() > 9 || tok.find_first_not_of("0123456789") != std::string::npos)
    fail(name, "index '" + tok + "' is not a non-negative integer", at);
  return std::strtoull(tok.c_str(), nullptr, 10);
}

struct Doc {
  std::map<std::string, const XMLElement*> ids;
  const std::string& name;
  const XMLElement* find(const char* ref, const XMLElement* at) const {
    if (ref == nullptr || ref[0] != '#') fail(name, std::string("a reference '") + (ref ? ref : "") + "' that is not '#id'", at);
    auto it = ids.find(ref + 1);
    if (it == ids.end()) fail(name, std::string("a reference to '") + ref + "', which this document does not define", at);
    return it->second;
  }
  // The number of elements an input's source gives: its accessor's count.
  uint64_t elements(const XMLElement* input, int depth = 0) const {
    const XMLElement* src = find(input->Attribute("source"), input);
    if (std::strcmp(src->Name(), "vertices") == 0 && depth == 0) {
      for (const XMLElement* in = src->FirstChildElement("input"); in; in = in->NextSiblingElement("input"))
        if (in->Attribute("semantic") && std::strcmp(in->Attribute("semantic"), "POSITION") == 0) return elements(in, 1);
      fail(name, "<vertices> without a POSITION input", src);
    }
    if (std::strcmp(src->Name(), "source") != 0) fail(name, "an input whose source is a <" + std::string(src->Name()) + ">", input);
    const XMLElement* tc = src->FirstChildElement("technique_common");
    const XMLElement* acc = tc ? tc->FirstChildElement("accessor") : nullptr;
    if (acc == nullptr) fail(name, "a <source> an input uses has no accessor", src);
    return count_attr(acc, "count", 0, name);
  }
};

void collect(const XMLElement* e, Doc& doc, int depth) {
  if (depth > 256) fail(doc.name, "elements nested over 256 deep", e);
  if (const char* id = e->Attribute("id")) doc.ids[id] = e;
  for (const XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) collect(c, doc, depth + 1);
}

bool is_array(const char* n) {
  return std::strcmp(n, "float_array") == 0 || std::strcmp(n, "int_array") == 0 || std::strcmp(n, "bool_array") == 0 ||
         std::strcmp(n, "Name_array") == 0 || std::strcmp(n, "IDREF_array") == 0;
}
bool is_primitive(const char* n) {
  for (const char* p : {"triangles", "polylist", "polygons", "tristrips", "trifans", "lines", "linestrips"})
    if (std::strcmp(n, p) == 0) return true;
  return false;
}

void check_primitive(const XMLElement* e, const Doc& doc) {
  const std::string& name = doc.name;
  std::vector<std::pair<uint64_t, uint64_t>> inputs;  // offset, elements
  uint64_t stride = 0;
  for (const XMLElement* in = e->FirstChildElement("input"); in; in = in->NextSiblingElement("input")) {
    const uint64_t off = count_attr(in, "offset", 0, name);
    inputs.emplace_back(off, doc.elements(in));
    if (off + 1 > stride) stride = off + 1;
  }
  if (inputs.empty()) fail(name, std::string("<") + e->Name() + "> without inputs", e);
  const uint64_t count = count_attr(e, "count", 0, name);
  uint64_t groups = 0;
  for (const XMLElement* p = e->FirstChildElement("p"); p; p = p->NextSiblingElement("p")) {
    const std::vector<std::string> t = tokens(p);
    if (t.size() % stride != 0)
      fail(name, "<p> holds " + std::to_string(t.size()) + " indices, not groups of " + std::to_string(stride), p);
    for (size_t i = 0; i < t.size(); ++i) {
      const uint64_t v = index_of(t[i], p, name);
      for (const auto& [off, n] : inputs)
        if (off == i % stride && v >= n)
          fail(name, "index " + std::to_string(v) + " names one of " + std::to_string(n) + " elements", p);
    }
    groups += t.size() / stride;
  }
  if (std::strcmp(e->Name(), "triangles") == 0 && groups != 3 * count)
    fail(name, "<triangles count=\"" + std::to_string(count) + "\"> holds " + std::to_string(groups) + " corners", e);
  if (std::strcmp(e->Name(), "polylist") == 0) {
    const XMLElement* vc = e->FirstChildElement("vcount");
    const std::vector<std::string> v = vc ? tokens(vc) : std::vector<std::string>{};
    if (v.size() != count) fail(name, "<polylist> of " + std::to_string(count) + " with " + std::to_string(v.size()) + " vcounts", e);
    uint64_t sum = 0;
    for (const std::string& s : v) sum += index_of(s, vc, name);
    if (sum != groups) fail(name, "<vcount> sums to " + std::to_string(sum) + ", <p> holds " + std::to_string(groups), e);
  }
}

void check(const XMLElement* e, const Doc& doc) {
  const std::string& name = doc.name;
  const char* n = e->Name();
  if (is_array(n)) {
    const uint64_t count = count_attr(e, "count", 0, name);
    const size_t have = tokens(e).size();
    if (have != count)
      fail(name, std::string("<") + n + " count=\"" + std::to_string(count) + "\"> holds " + std::to_string(have) + " values", e);
  } else if (std::strcmp(n, "accessor") == 0) {
    const XMLElement* arr = doc.find(e->Attribute("source"), e);
    if (!is_array(arr->Name())) fail(name, "an accessor of a <" + std::string(arr->Name()) + ">", e);
    const uint64_t count = count_attr(e, "count", 0, name), stride = count_attr(e, "stride", 1, name);
    const uint64_t offset = count_attr(e, "offset", 0, name), values = count_attr(arr, "count", 0, name);
    uint64_t params = 0;
    for (const XMLElement* p = e->FirstChildElement("param"); p; p = p->NextSiblingElement("param")) ++params;
    if (stride < params || stride == 0) fail(name, "an accessor of stride " + std::to_string(stride) + " with " + std::to_string(params) + " params", e);
    if (count > 0 && offset + count * stride > values)
      fail(name, "an accessor of " + std::to_string(count) + " x " + std::to_string(stride) + " from " +
                     std::to_string(offset) + " in an array of " + std::to_string(values),
           e);
  } else if (is_primitive(n)) {
    check_primitive(e, doc);
  }
  for (const XMLElement* c = e->FirstChildElement(); c; c = c->NextSiblingElement()) check(c, doc);
}

}  // namespace

void check_collada(const uint8_t* data, size_t size, const std::string& name) {
  tinyxml2::XMLDocument xml;
  if (xml.Parse(reinterpret_cast<const char*>(data), size) != tinyxml2::XML_SUCCESS)
    throw std::runtime_error(name + ": not an XML document (" + std::string(xml.ErrorStr() ? xml.ErrorStr() : "") + ")");
  const XMLElement* root = xml.RootElement();
  if (root == nullptr || std::strcmp(root->Name(), "COLLADA") != 0) throw std::runtime_error(name + ": not a Collada document (no <COLLADA> root)");
  Doc doc{{}, name};
  collect(root, doc, 0);
  check(root, doc);
}

}  // namespace vds::enc
