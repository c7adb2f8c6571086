#include "scene.hpp"

#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>

namespace sample {

int Scene::add(std::string name, int parent, glm::vec3 translation, glm::vec3 scale) {
  if (parent >= int(nodes_.size())) throw std::invalid_argument("scene node parent must be added first");
  SceneNode node;
  node.name = std::move(name);
  node.parent = parent;
  node.translation = translation;
  node.scale = scale;
  nodes_.push_back(std::move(node));
  return int(nodes_.size()) - 1;
}

void Scene::update() {
  for (SceneNode& n : nodes_) {
    const glm::mat4 local = glm::translate(glm::mat4(1.0f), n.translation) * glm::mat4_cast(n.rotation) *
                            glm::scale(glm::mat4(1.0f), n.scale);
    n.world = n.parent < 0 ? local : nodes_[std::size_t(n.parent)].world * local;
  }
}

}  // namespace sample
