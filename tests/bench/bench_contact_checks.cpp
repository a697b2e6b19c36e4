#include "bench_contact_checks.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <sstream>

namespace torsion::bench {

namespace {

using Vec = Eigen::Vector3d;

// Closest point to p on triangle abc (the Voronoi-region walk of Ericson's Real-Time Collision
// Detection, 5.1.5), as a distance.
double distanceToTriangle(const Vec& p, const Vec& a, const Vec& b, const Vec& c) {
  const Vec ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Vec bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Vec cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denom = 1 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

double signedVolume(const Vec& a, const Vec& b, const Vec& c, const Vec& d) {
  return (b - a).dot((c - a).cross(d - a));
}

// p inside the deformed tet (its four sub-volumes all of the tet's sign; a node on a face counts).
bool insideTet(const Vec& p, const Vec& a, const Vec& b, const Vec& c, const Vec& d) {
  const double v = signedVolume(a, b, c, d);
  if (v == 0) return false;
  const double s = v > 0 ? 1 : -1;
  return s * signedVolume(p, b, c, d) >= 0 && s * signedVolume(a, p, c, d) >= 0 &&
         s * signedVolume(a, b, p, d) >= 0 && s * signedVolume(a, b, c, p) >= 0;
}

Vec centroid(const std::vector<Vec>& nodes) {
  Vec c = Vec::Zero();
  for (const Vec& p : nodes)
    c += p;
  return nodes.empty() ? c : Vec(c / static_cast<double>(nodes.size()));
}

double lowestZ(const std::vector<Vec>& nodes) {
  double z = std::numeric_limits<double>::infinity();
  for (const Vec& p : nodes)
    z = std::min(z, p.z());
  return z;
}

int bodyIndex(const scene::SceneSpec& spec, const std::string& name) {
  for (size_t i = 0; i < spec.bodies.size(); ++i)
    if (spec.bodies[i].name == name) return static_cast<int>(i);
  return -1;
}

bool hasBodies(const scene::SceneSpec& spec, std::initializer_list<const char*> names) {
  for (const char* name : names)
    if (bodyIndex(spec, name) < 0) return false;
  return true;
}

}  // namespace

Penetration interpenetration(const std::vector<TetMesh>& rest, const NodeField& x,
                             double tolerance) {
  Penetration result;
  for (size_t b = 0; b < rest.size(); ++b) {
    const std::vector<Vec>& xb = x[b];
    Eigen::AlignedBox3d box;
    for (const Vec& p : xb)
      box.extend(p);
    for (size_t a = 0; a < rest.size(); ++a) {
      if (a == b) continue;
      for (const Vec& p : x[a]) {
        if (!box.contains(p)) continue;
        bool inside = false;
        for (const Tet& t : rest[b].tets()) {
          if (insideTet(p, xb[size_t(t[0])], xb[size_t(t[1])], xb[size_t(t[2])],
                        xb[size_t(t[3])])) {
            inside = true;
            break;
          }
        }
        if (!inside) continue;
        double depth = std::numeric_limits<double>::infinity();
        for (const Triangle& f : rest[b].surfaceTriangles())
          depth = std::min(
              depth, distanceToTriangle(p, xb[size_t(f[0])], xb[size_t(f[1])], xb[size_t(f[2])]));
        result.deepest = std::max(result.deepest, depth);
        if (depth > tolerance) ++result.nodes_beyond;
      }
    }
  }
  return result;
}

std::vector<std::vector<double>> lumpedMasses(const scene::SceneSpec& spec,
                                              const std::vector<TetMesh>& rest) {
  std::vector<std::vector<double>> masses;
  for (size_t b = 0; b < rest.size(); ++b) {
    std::vector<double> m(static_cast<size_t>(rest[b].nodeCount()), 0);
    for (int t = 0; t < rest[b].tetCount(); ++t)
      for (int corner : rest[b].tets()[static_cast<size_t>(t)])
        m[static_cast<size_t>(corner)] +=
            spec.bodies[b].material.density * rest[b].restVolume(t) / 4;
    masses.push_back(std::move(m));
  }
  return masses;
}

Motion motionOf(const std::vector<std::vector<double>>& masses, const NodeField& x,
                const NodeField& v) {
  Motion motion;
  double total = 0;
  for (size_t b = 0; b < masses.size(); ++b) {
    for (size_t i = 0; i < masses[b].size(); ++i) {
      const double m = masses[b][i];
      motion.momentum += m * v[b][i];
      motion.kinetic_energy += 0.5 * m * v[b][i].squaredNorm();
      motion.centre += m * x[b][i];
      total += m;
    }
  }
  if (total > 0) motion.centre /= total;
  return motion;
}

NodeField initialVelocities(const scene::SceneSpec& spec, const std::vector<TetMesh>& rest,
                            const std::vector<std::vector<double>>& masses) {
  NodeField v;
  for (size_t b = 0; b < rest.size(); ++b) {
    const std::vector<Vec>& x = rest[b].restPositions();
    Vec c = Vec::Zero();
    double total = 0;
    for (size_t i = 0; i < x.size(); ++i) {
      c += masses[b][i] * x[i];
      total += masses[b][i];
    }
    if (total > 0) c /= total;
    std::vector<Vec> vb;
    for (const Vec& p : x)
      vb.push_back(spec.bodies[b].linear_velocity + spec.bodies[b].angular_velocity.cross(p - c));
    v.push_back(std::move(vb));
  }
  return v;
}

ContactVerdict judgeContact(const scene::SceneSpec& spec, const std::vector<TetMesh>& rest,
                            const std::vector<std::vector<double>>& masses, const Motion& start,
                            const ContactEnd& end, double tolerance) {
  ContactVerdict v;
  std::ostringstream d;
  if (!end.finite || end.nodes.size() != rest.size()) {
    v.outcome = "failed";
    v.detail = !end.finite ? "non-finite state" : "incomplete end state";
    return v;
  }
  v.passed_through = end.at_end.deepest > tolerance || end.worst.deepest > tolerance;
  d << "deepest node inside another body " << end.at_end.deepest << " m at the end, "
    << end.worst.deepest << " m at worst (step " << end.worst_step << ", " << end.worst.nodes_beyond
    << " nodes beyond " << tolerance << " m)";

  const bool free_bodies = spec.world.gravity.isZero() && !spec.ground && spec.rigid_bodies.empty();
  if (free_bodies && end.velocities.size() == rest.size()) {
    const Motion now = motionOf(masses, end.nodes, end.velocities);
    double scale = 0;  // sum of m |v0|: the momentum the bodies brought in
    const NodeField v0 = initialVelocities(spec, rest, masses);
    for (size_t b = 0; b < masses.size(); ++b)
      for (size_t i = 0; i < masses[b].size(); ++i)
        scale += masses[b][i] * v0[b][i].norm();
    const double change = (now.momentum - start.momentum).norm();
    v.momentum = change <= 0.05 * scale ? "kept" : "lost";
    v.energy_gained = now.kinetic_energy > 1.05 * start.kinetic_energy;
    d << "; momentum change " << change << " N s of " << scale << " brought in; kinetic energy "
      << start.kinetic_energy << " -> " << now.kinetic_energy << " J; centre of mass moved "
      << (now.centre - start.centre).norm() << " m";
  }

  bool ok = true;
  if (spec.name == "bullet_collide_soft" && hasBodies(spec, {"lower", "upper"})) {
    // Head-on at 15 m/s each along z (offset 1 m in x): the lower cube stays below the upper.
    const Vec lower = centroid(end.nodes[size_t(bodyIndex(spec, "lower"))]);
    const Vec upper = centroid(end.nodes[size_t(bodyIndex(spec, "upper"))]);
    ok = lower.z() < upper.z();
    d << "; centroids z lower " << lower.z() << ", upper " << upper.z();
  } else if (spec.name == "soft_stack" && hasBodies(spec, {"bottom", "middle", "top"})) {
    // Three 0.2 m blocks stacked, a ball dropped on them (it bounces off the top block and rolls
    // onto the ground): the blocks still in order, the top one over the bottom one within a
    // quarter block. That no body ends inside another is the interpenetration check's.
    const char* order[] = {"bottom", "middle", "top"};
    double below = -std::numeric_limits<double>::infinity();
    for (const char* name : order) {
      const Vec c = centroid(end.nodes[size_t(bodyIndex(spec, name))]);
      ok = ok && c.z() > below;
      below = c.z();
      d << "; " << name << " z " << c.z();
    }
    const Vec bottom = centroid(end.nodes[size_t(bodyIndex(spec, "bottom"))]);
    const Vec top = centroid(end.nodes[size_t(bodyIndex(spec, "top"))]);
    ok = ok && (top - bottom).head<2>().norm() < 0.05;
    d << "; top off bottom " << (top - bottom).head<2>().norm() << " m";
    if (const int ball = bodyIndex(spec, "ball"); ball >= 0) {
      const Vec c = centroid(end.nodes[size_t(ball)]);
      d << "; ball at (" << c.x() << ", " << c.y() << ", " << c.z() << ")";
    }
  } else if (spec.name == "soft_grasp" && hasBodies(spec, {"object"})) {
    // The fingers rise 0.3 m while squeezing: the object, held by friction, rises with them.
    const int object = bodyIndex(spec, "object");
    const double lift =
        lowestZ(end.nodes[size_t(object)]) - lowestZ(rest[size_t(object)].restPositions());
    ok = lift > 0.2;
    d << "; object lifted " << lift << " m";
  } else {
    v.detail = d.str();
    return v;
  }
  v.outcome = ok ? "ok" : "failed";
  v.detail = d.str();
  return v;
}

}  // namespace torsion::bench
