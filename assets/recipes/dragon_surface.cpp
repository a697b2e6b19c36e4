// Recipe helper (not part of the Torsion build): turns CGAL's ChineseDragon-10kv.off into a
// closed, self-intersection-free surface of about a thousand vertices, ready for
// `torsion mesh tetrahedralize`. Compiled by make_assets.sh against Debian's libcgal-dev.
//
// The source surface has two tiny holes and ~100 pairs of intersecting triangles, which plain
// decimation keeps; so the surface is first alpha-wrapped (CGAL::alpha_wrap_3: watertight,
// 2-manifold, intersection-free by construction), then isotropically remeshed to the target edge
// length (which sets the vertex count), then checked.
//
// Orientation of the output: the figure (a seated guardian lion) stands with the flat underside of
// its base on z = 0, up along +z, its face towards -y, its bounding box centred on x = y = 0.
// That is the source rotated about x by `tilt` degrees (90 would take the source's +y to +z; the
// base plane of the source is tilted 17.5 degrees from that, hence 72.5), scaled by `scale`, and
// moved. (17.5 is the tilt that puts the most source vertices within 0.5 units of one support
// plane.)
//
// usage: dragon_surface IN.off OUT.off [alpha_div offset_div edge_div scale tilt iterations]
//   alpha = diag / alpha_div, offset = diag / offset_div, edge length = diag / edge_div, where diag
//   is the bounding-box diagonal of the scaled source.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/OFF.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point>;
namespace PMP = CGAL::Polygon_mesh_processing;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: dragon_surface IN.off OUT.off [alpha_div offset_div edge_div scale tilt "
                 "iterations]\n";
    return 2;
  }
  const double alpha_div = argc > 3 ? std::atof(argv[3]) : 35;
  const double offset_div = argc > 4 ? std::atof(argv[4]) : 1050;
  const double edge_div = argc > 5 ? std::atof(argv[5]) : 28;
  const double scale = argc > 6 ? std::atof(argv[6]) : 0.1;
  const double tilt = (argc > 7 ? std::atof(argv[7]) : 72.5) * CGAL_PI / 180;
  const int iterations = argc > 8 ? std::atoi(argv[8]) : 5;

  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> polygons;
  if (!CGAL::IO::read_polygon_soup(argv[1], points, polygons) || points.empty()) {
    std::cerr << argv[1] << ": cannot read the surface\n";
    return 1;
  }
  // Rotate about x by the tilt and scale.
  const double c = std::cos(tilt), s = std::sin(tilt);
  for (Point& p : points) {
    p = Point(scale * p.x(), scale * (c * p.y() - s * p.z()), scale * (s * p.y() + c * p.z()));
  }
  CGAL::Bbox_3 box;
  for (const Point& p : points)
    box += p.bbox();
  const double diag =
      std::sqrt(CGAL::square(box.xmax() - box.xmin()) + CGAL::square(box.ymax() - box.ymin()) +
                CGAL::square(box.zmax() - box.zmin()));

  Mesh mesh;
  CGAL::alpha_wrap_3(points, polygons, diag / alpha_div, diag / offset_div, mesh);
  std::cerr << "alpha wrap: " << num_vertices(mesh) << " vertices, " << num_faces(mesh)
            << " triangles\n";
  PMP::isotropic_remeshing(faces(mesh), diag / edge_div, mesh,
                           CGAL::parameters::number_of_iterations(iterations));
  mesh.collect_garbage();
  std::cerr << "remeshed:   " << num_vertices(mesh) << " vertices, " << num_faces(mesh)
            << " triangles\n";

  // Stand it on z = 0, centred on the z axis.
  CGAL::Bbox_3 out_box;
  for (const auto v : vertices(mesh))
    out_box += mesh.point(v).bbox();
  const double cx = 0.5 * (out_box.xmin() + out_box.xmax());
  const double cy = 0.5 * (out_box.ymin() + out_box.ymax());
  const double z0 = out_box.zmin();
  for (const auto v : vertices(mesh)) {
    const Point& p = mesh.point(v);
    mesh.point(v) = Point(p.x() - cx, p.y() - cy, p.z() - z0);
  }

  const bool closed = CGAL::is_closed(mesh);
  const bool intersecting = PMP::does_self_intersect(mesh);
  std::cerr << "closed: " << (closed ? "yes" : "NO")
            << ", self-intersecting: " << (intersecting ? "YES" : "no") << "\n";
  if (!closed || intersecting) return 1;

  std::ofstream out(argv[2]);
  out.precision(17);
  if (!CGAL::IO::write_OFF(out, mesh) || !out) {
    std::cerr << argv[2] << ": cannot write\n";
    return 1;
  }
  return 0;
}
