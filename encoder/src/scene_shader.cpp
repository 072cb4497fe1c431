// vds encoder: Quake III shader scripts reduced to what a walkthrough draws
// (vds/enc/scene.h, read_shader_script). The rule:
// - the shader's image is its first stage's `map`, `clampMap` or `animMap`
//   (first frame) that names an image ($lightmap and $whiteimage are not
//   images); a shader without one uses its `qer_editorimage`; a sky shader
//   without one uses its skyParms far box (the _ft side);
// - that stage's blend decides how the surface is drawn: `blendFunc add`
//   (GL_ONE GL_ONE) is an additive effect; `blendFunc blend`
//   (GL_SRC_ALPHA GL_ONE_MINUS_SRC_ALPHA) or any `alphaFunc` is alpha-tested
//   at one half; anything else is opaque;
// - `rgbGen vertex`, `exactVertex` or `lightingDiffuse` in that stage light
//   it by the vertex colours; a stage `map $lightmap` anywhere marks the
//   shader lightmapped;
// - `surfaceparm sky`, `fog`, `nodraw` and `cull none|disable|twosided`
//   are kept; everything else (texture animation, deforms, later stages) is
//   dropped.
#include <cctype>
#include <stdexcept>
#include <string>
#include <vector>

#include "text.h"
#include "vds/enc/scene.h"

namespace vds::enc {
namespace {

// Tokens of a script with the line each starts on; comments (// and /* */)
// removed, quotes kept together.
struct Token {
  std::string text;
  int line;
};

std::vector<Token> tokenize(const std::string& text, const std::string& name) {
  std::vector<Token> out;
  int line = 1;
  size_t i = 0;
  const size_t n = text.size();
  while (i < n) {
    const char c = text[i];
    if (c == '\n') {
      ++line, ++i;
    } else if (std::isspace(static_cast<unsigned char>(c)) || c == '\0') {
      ++i;
    } else if (c == '/' && i + 1 < n && text[i + 1] == '/') {
      while (i < n && text[i] != '\n') ++i;
    } else if (c == '/' && i + 1 < n && text[i + 1] == '*') {
      const int start = line;
      i += 2;
      while (i + 1 < n && !(text[i] == '*' && text[i + 1] == '/')) line += text[i++] == '\n';
      if (i + 1 >= n) throw std::runtime_error(name + ": a comment opened on line " + std::to_string(start) + " is not closed");
      i += 2;
    } else if (c == '{' || c == '}') {
      out.push_back({std::string(1, c), line});
      ++i;
    } else if (c == '"') {
      const size_t end = text.find('"', i + 1);
      if (end == std::string::npos || text.find('\n', i) < end)
        throw std::runtime_error(name + ": a quote on line " + std::to_string(line) + " is not closed on its line");
      out.push_back({text.substr(i + 1, end - i - 1), line});
      i = end + 1;
    } else {
      const size_t start = i;
      while (i < n && !std::isspace(static_cast<unsigned char>(text[i])) && text[i] != '{' && text[i] != '}' &&
             text[i] != '"' && !(text[i] == '/' && i + 1 < n && (text[i + 1] == '/' || text[i + 1] == '*')))
        ++i;
      out.push_back({text.substr(start, i - start), line});
    }
  }
  return out;
}

bool is_image(const std::string& s) { return !s.empty() && s[0] != '$' && s != "*white"; }

struct Stage {
  std::string image;
  bool lightmap = false, additive = false, alpha = false, vertex = false;
};

}  // namespace

void read_shader_script(const std::string& text, const std::string& name, ShaderTable* table) {
  const std::vector<Token> t = tokenize(text, name);
  size_t i = 0;
  const auto fail = [&](const std::string& what, int line) {
    throw std::runtime_error(name + ": " + what + " (line " + std::to_string(line) + ")");
  };
  // The rest of token i's line, from i + 1.
  const auto args = [&](size_t k) {
    std::vector<std::string> a;
    const int line = t[k].line;
    for (size_t j = k + 1; j < t.size() && t[j].line == line && t[j].text != "{" && t[j].text != "}"; ++j)
      a.push_back(t[j].text);
    return a;
  };
  while (i < t.size()) {
    const std::string shader = ascii_lower(t[i].text);
    const int at = t[i].line;
    if (shader == "{" || shader == "}") fail("a brace where a shader name should be", at);
    if (i + 1 >= t.size() || t[i + 1].text != "{") fail("shader '" + t[i].text + "' has no body", at);
    i += 2;
    ShaderInfo info;
    std::string editor_image, farbox;
    std::vector<Stage> stages;
    bool closed = false;
    while (i < t.size()) {
      const std::string key = ascii_lower(t[i].text);
      if (key == "}") {
        ++i;
        closed = true;
        break;
      }
      if (key == "{") {
        // A stage.
        const int stage_line = t[i].line;
        ++i;
        Stage st;
        bool stage_closed = false;
        while (i < t.size()) {
          const std::string k = ascii_lower(t[i].text);
          if (k == "}") {
            ++i;
            stage_closed = true;
            break;
          }
          if (k == "{") fail("a stage inside a stage", t[i].line);
          const std::vector<std::string> a = args(i);
          if ((k == "map" || k == "clampmap") && !a.empty()) {
            if (ascii_lower(a[0]) == "$lightmap") st.lightmap = true;
            else if (is_image(a[0]) && st.image.empty()) st.image = a[0];
          } else if (k == "animmap" && a.size() >= 2 && is_image(a[1]) && st.image.empty()) {
            st.image = a[1];
          } else if (k == "blendfunc" && !a.empty()) {
            const std::string b0 = ascii_lower(a[0]), b1 = a.size() > 1 ? ascii_lower(a[1]) : "";
            st.additive = b0 == "add" || (b0 == "gl_one" && b1 == "gl_one");
            st.alpha = st.alpha || b0 == "blend" || (b0 == "gl_src_alpha" && b1 == "gl_one_minus_src_alpha");
          } else if (k == "alphafunc") {
            st.alpha = true;
          } else if (k == "rgbgen" && !a.empty()) {
            const std::string g = ascii_lower(a[0]);
            st.vertex = g == "vertex" || g == "exactvertex" || g == "lightingdiffuse";
          }
          i += 1 + a.size();
        }
        if (!stage_closed) fail("a stage of shader '" + shader + "' is not closed", stage_line);
        stages.push_back(st);
        continue;
      }
      const std::vector<std::string> a = args(i);
      if (key == "surfaceparm" && !a.empty()) {
        const std::string p = ascii_lower(a[0]);
        info.sky = info.sky || p == "sky";
        info.fog = info.fog || p == "fog";
        info.nodraw = info.nodraw || p == "nodraw";
      } else if (key == "cull" && !a.empty()) {
        const std::string c = ascii_lower(a[0]);
        info.two_sided = c == "none" || c == "disable" || c == "twosided";
      } else if (key == "qer_editorimage" && !a.empty()) {
        editor_image = a[0];
      } else if (key == "skyparms" && !a.empty() && a[0] != "-") {
        farbox = a[0] + "_ft";
      }
      i += 1 + a.size();
    }
    if (!closed) fail("shader '" + shader + "' is not closed", at);
    info.stages = static_cast<int>(stages.size());
    for (const Stage& st : stages) info.lightmapped = info.lightmapped || st.lightmap;
    for (const Stage& st : stages) {
      if (st.image.empty()) continue;
      info.image = st.image;
      info.blend = st.additive ? ShaderBlend::additive : st.alpha ? ShaderBlend::alpha_test : ShaderBlend::opaque;
      info.vertex_colour = st.vertex;
      break;
    }
    if (info.image.empty()) info.image = info.sky && !farbox.empty() ? farbox : editor_image;
    (*table)[shader] = info;
  }
}

}  // namespace vds::enc
