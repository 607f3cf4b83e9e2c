#include "scene/obj_reader.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <utility>

#include "scene/scene_messages.h"

namespace drape::bake::detail {

Status ReadObj(const std::string& file, const std::string& where, std::vector<Float3>* positions,
               std::vector<uint32_t>* triangles, std::vector<Float3>* colors) {
  std::ifstream in(file);
  std::vector<Float3> read_colors;
  bool every_vertex_colored = true;
  if (!in) return Invalid(where + ": cannot open " + Quote(file));
  std::string line;
  uint32_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    std::istringstream tokens(line);
    std::string tag;
    if (!(tokens >> tag) || tag[0] == '#') continue;
    const std::string at = where + ": " + Quote(file) + " line " + std::to_string(line_number);
    if (tag == "v") {
      double x = 0, y = 0, z = 0;
      if (!(tokens >> x >> y >> z) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
        return Invalid(at + ": a vertex needs 3 finite coordinates");
      }
      positions->push_back({static_cast<float>(x), static_cast<float>(y), static_cast<float>(z)});
      double r = 0, g = 0, b = 0;
      if (tokens >> r >> g >> b) {
        if (!(r >= 0 && r <= 1 && g >= 0 && g <= 1 && b >= 0 && b <= 1))
          return Invalid(at + ": a vertex colour needs 3 channels in [0, 1]");
        read_colors.push_back(
            {static_cast<float>(r), static_cast<float>(g), static_cast<float>(b)});
      } else {
        every_vertex_colored = false;
      }
    } else if (tag == "f") {
      std::vector<uint32_t> face;
      std::string corner;
      while (tokens >> corner) {
        long long index = 0;
        try {
          index = std::stoll(corner.substr(0, corner.find('/')));
        } catch (...) {
          return Invalid(at + ": bad face corner " + Quote(corner));
        }
        const long long count = static_cast<long long>(positions->size());
        if (index < 0) index += count + 1;  // relative to the vertices read so far
        if (index < 1 || index > count) {
          return Invalid(at + ": face index " + corner + " is out of range (" +
                         std::to_string(count) + " vertices so far)");
        }
        face.push_back(static_cast<uint32_t>(index - 1));
      }
      if (face.size() < 3) return Invalid(at + ": a face needs at least 3 corners");
      for (size_t k = 1; k + 1 < face.size(); ++k) {  // fan: convex polygons
        triangles->insert(triangles->end(), {face[0], face[k], face[k + 1]});
      }
    }
  }
  if (positions->empty() || triangles->empty())
    return Invalid(where + ": " + Quote(file) + " holds no triangles");
  if (colors != nullptr) {
    colors->clear();
    if (every_vertex_colored) *colors = std::move(read_colors);
  }
  return Status::Ok();
}

}  // namespace drape::bake::detail
