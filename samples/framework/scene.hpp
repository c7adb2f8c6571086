#pragma once
// The viewer's scene hierarchy (the thesis' version 1): nodes with a local translate/rotate/scale whose transforms
// compose down the tree, so moving a node moves its children. Nodes are stored parent-before-child.
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace sample {

struct SceneNode {
  std::string name;
  int parent = -1;  // index of an earlier node, -1 for a root
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 scale{1.0f};
  glm::mat4 world{1.0f};  // updated by Scene::update()
};

class Scene {
 public:
  // Adds a node under `parent` (-1 for a root); returns its index.
  int add(std::string name, int parent = -1, glm::vec3 translation = glm::vec3(0.0f),
          glm::vec3 scale = glm::vec3(1.0f));
  SceneNode& node(int index) { return nodes_[std::size_t(index)]; }
  const SceneNode& node(int index) const { return nodes_[std::size_t(index)]; }
  int size() const { return int(nodes_.size()); }
  // Recomputes every world matrix, parents first.
  void update();

 private:
  std::vector<SceneNode> nodes_;
};

}  // namespace sample
