#include "torsion/contact/surface_tree.h"

#include <algorithm>

#include "torsion/bt_conversions.h"

namespace torsion {

namespace {

// Leaf indices under `node` whose boxes overlap `box`. Recursive rather than btDbvt::collideTV,
// which allocates its stack on every call: queries run per surface node and edge, from several
// threads at once, and only read the tree.
void collect(const btDbvtNode* node, const btDbvtVolume& box, std::vector<int>& out) {
  if (!Intersect(node->volume, box)) return;
  if (node->isleaf()) {
    out.push_back(node->dataAsInt);
    return;
  }
  collect(node->childs[0], box, out);
  collect(node->childs[1], box, out);
}

btDbvtVolume boxOf(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  // Float Bullet rounds the corners: widen by one float ulp of the extent so no overlap is lost.
  const Eigen::Vector3d slack = Eigen::Vector3d::Constant(
      kBulletEpsilon * (1.0 + std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff())));
  return btDbvtVolume::FromMM(toBt(lo - slack), toBt(hi + slack));
}

}  // namespace

SurfaceTree::SurfaceTree(std::vector<Triangle> triangles) : triangles_(std::move(triangles)) {}

SurfaceTree::~SurfaceTree() {
  tree_.clear();
}

void SurfaceTree::setBoxes(const Eigen::VectorXd& start, const Eigen::VectorXd& end, double pad) {
  boxes_.resize(triangles_.size());
  for (size_t t = 0; t < triangles_.size(); ++t) {
    Eigen::Vector3d lo = start.segment<3>(3 * triangles_[t][0]);
    Eigen::Vector3d hi = lo;
    for (int corner : triangles_[t]) {
      for (const Eigen::VectorXd* x : {&start, &end}) {
        lo = lo.cwiseMin(x->segment<3>(3 * corner));
        hi = hi.cwiseMax(x->segment<3>(3 * corner));
      }
    }
    boxes_[t] = boxOf(lo - Eigen::Vector3d::Constant(pad), hi + Eigen::Vector3d::Constant(pad));
  }
}

void SurfaceTree::refit(const Eigen::VectorXd& start, const Eigen::VectorXd& end, double pad) {
  setBoxes(start, end, pad);
  const bool first = leaves_.empty();
  if (first) leaves_.resize(triangles_.size());
  for (size_t t = 0; t < triangles_.size(); ++t) {
    btDbvtVolume volume = boxes_[t];
    if (first) {
      leaves_[t] = tree_.insert(volume, nullptr);
      leaves_[t]->dataAsInt = static_cast<int>(t);
    } else {
      tree_.update(leaves_[t], volume);
    }
  }
}

btDbvtVolume SurfaceTree::queryBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  return boxOf(lo, hi);
}

void SurfaceTree::query(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                        std::vector<int>& out) const {
  out.clear();
  if (tree_.m_root == nullptr) return;
  collect(tree_.m_root, boxOf(lo, hi), out);
  std::sort(out.begin(), out.end());
}

}  // namespace torsion
