// vds encoder: a Collada (.dae) document checked before assimp sees it:
// assimp's Collada loader takes an array's declared count, an accessor's
// count and stride and a primitive's indices as given (a float_array whose
// count says 0 while it holds nine numbers crashed it). The rules checked
// are those of the COLLADA 1.4.1 specification (Khronos), chapter 5
// (<float_array>, <accessor>, <input>, <p>, <vcount>).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

namespace vds::enc {

// Throws std::runtime_error "NAME: what is wrong (line N)" unless: the file
// is well-formed XML (tinyxml2, nesting at most its limit) with a <COLLADA>
// root; every value array's count is the number of values it holds (at
// most 2^24); every accessor names an array of this document ("#id") and
// count x stride + offset lies within it, stride at least its params;
// every primitive (triangles, polylist, polygons, tristrips, trifans,
// lines, linestrips) has inputs whose sources resolve (to a <source> with
// an accessor, or to <vertices> whose POSITION does), its <p> holds whole
// index groups (a multiple of the largest input offset + 1), every index
// names an element of its input's accessor, triangles hold 3 x count
// groups and a polylist's <vcount> has count entries summing to its groups.
void check_collada(const uint8_t* data, size_t size, const std::string& name);

}  // namespace vds::enc
