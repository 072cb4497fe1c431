// Shader scripts (vds/enc/scene.h, read_shader_script): each texture
// reduced to its first image stage by the stated rule; broken scripts
// refused naming the file and the line; the installed scripts all read and
// a map's scripted textures all resolve to images.
#include <gtest/gtest.h>

#include <string>

#include "vds/enc/scene.h"

namespace {

using vds::enc::ShaderBlend;
using vds::enc::ShaderTable;

ShaderTable read(const std::string& text) {
  ShaderTable t;
  vds::enc::read_shader_script(text, "s.shader", &t);
  return t;
}

std::string refusal(const std::string& text) {
  try {
    read(text);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(SceneShader, TheFirstImageStageIsTheTexture) {
  const ShaderTable t = read(
      "// a comment\n"
      "textures/a/lit\n{\n\tqer_editorimage textures/a/editor.tga\n\tsurfaceparm nomarks\n"
      "\t{\n\t\tmap $lightmap\n\t\trgbGen identity\n\t}\n"
      "\t{\n\t\tmap textures/a/wall.tga\n\t\tblendFunc GL_DST_COLOR GL_ZERO\n\t}\n"
      "\t{\n\t\tmap textures/a/glow.tga\n\t\tblendfunc add\n\t}\n}\n"
      "textures/a/Effect /* inline */ {\n{\nanimMap 8 textures/a/f1.tga textures/a/f2.tga\nblendFunc GL_ONE GL_ONE\n}\ncull none\n}\n"
      "textures/a/grate\n{\n{\nclampmap textures/a/grate.tga\nalphaFunc GE128\nrgbGen vertex\n}\n}\n"
      "textures/a/sky\n{\nsurfaceparm sky\nskyparms env/space - -\n}\n"
      "textures/a/fogvol\n{\nsurfaceparm fog\nsurfaceparm nodraw\nqer_editorimage textures/a/fog.tga\n}\n");
  ASSERT_EQ(t.size(), 5u);
  const auto& lit = t.at("textures/a/lit");
  EXPECT_EQ(lit.image, "textures/a/wall.tga");
  EXPECT_EQ(lit.blend, ShaderBlend::opaque);
  EXPECT_TRUE(lit.lightmapped);
  EXPECT_EQ(lit.stages, 3);
  const auto& fx = t.at("textures/a/effect");  // names without case
  EXPECT_EQ(fx.image, "textures/a/f1.tga");
  EXPECT_EQ(fx.blend, ShaderBlend::additive);
  EXPECT_TRUE(fx.two_sided);
  const auto& grate = t.at("textures/a/grate");
  EXPECT_EQ(grate.image, "textures/a/grate.tga");
  EXPECT_EQ(grate.blend, ShaderBlend::alpha_test);
  EXPECT_TRUE(grate.vertex_colour);
  EXPECT_FALSE(grate.lightmapped);
  const auto& sky = t.at("textures/a/sky");
  EXPECT_TRUE(sky.sky);
  EXPECT_EQ(sky.image, "env/space_ft");
  const auto& fog = t.at("textures/a/fogvol");
  EXPECT_TRUE(fog.fog && fog.nodraw);
  EXPECT_EQ(fog.image, "textures/a/fog.tga");
}

TEST(SceneShader, ALaterDefinitionReplacesAnEarlierOne) {
  ShaderTable t;
  vds::enc::read_shader_script("x\n{\n{\nmap a.tga\n}\n}\n", "1.shader", &t);
  vds::enc::read_shader_script("x\n{\n{\nmap b.tga\n}\n}\n", "2.shader", &t);
  EXPECT_EQ(t.at("x").image, "b.tga");
}

TEST(SceneShader, BrokenScriptsAreRefusedWithTheLine) {
  EXPECT_EQ(refusal("a\n{\n{\nmap x.tga\n}\n"), "s.shader: shader 'a' is not closed (line 1)");
  EXPECT_EQ(refusal("a\n{\n{\nmap x.tga\n"), "s.shader: a stage of shader 'a' is not closed (line 3)");
  EXPECT_EQ(refusal("a\n{\n{\n{\n}\n}\n}\n"), "s.shader: a stage inside a stage (line 4)");
  EXPECT_EQ(refusal("a\n{\n}\n}\n"), "s.shader: a brace where a shader name should be (line 4)");
  EXPECT_EQ(refusal("a\nb\n"), "s.shader: shader 'a' has no body (line 1)");
  EXPECT_EQ(refusal("a\n{\n/* never closed\n}\n"), "s.shader: a comment opened on line 3 is not closed");
  EXPECT_EQ(refusal("a\n{\nq \"open\n}\n"), "s.shader: a quote on line 3 is not closed on its line");
  EXPECT_EQ(refusal(""), "");
  EXPECT_EQ(refusal("// only a comment\n"), "");
}

TEST(SceneShader, EveryPrefixOfAScriptIsReadOrRefusedCleanly) {
  const std::string s = "textures/a/b\n{\n\tsurfaceparm sky // x\n\t{\n\t\tmap \"textures/a b.tga\"\n\t\tblendfunc add\n\t}\n}\n";
  for (size_t n = 0; n <= s.size(); ++n) {
    const std::string r = refusal(s.substr(0, n));
    if (!r.empty()) EXPECT_EQ(r.rfind("s.shader: ", 0), 0u) << r;
  }
  EXPECT_EQ(read(s).at("textures/a/b").image, "textures/a b.tga");
}

TEST(SceneShader, TheInstalledMapsResolveEveryScriptedTexture) {
  // openarena-data's scripts (scripts/fetch-data.sh): every script reads,
  // and on the maps the figures use every used texture has an image.
  for (const char* map : {"oa_dm4", "oa_dm5", "oa_rpg3dm2"}) {
    const vds::enc::Scene s = vds::enc::load_scene(map);
    size_t scripted = 0;
    std::vector<bool> used(s.textures.size());
    for (const auto& f : s.surfaces) used[static_cast<size_t>(f.texture)] = true;
    for (size_t t = 0; t < s.textures.size(); ++t) {
      if (!used[t]) continue;
      scripted += s.textures[t].scripted;
      EXPECT_FALSE(s.textures[t].file.empty()) << map << ": " << s.textures[t].name;
    }
    EXPECT_GE(scripted, 5u) << map;
  }
}

}  // namespace
