// Peer of the projection reconstruction (issue 14): CGAL's advancing front
// surface reconstruction with its default parameters, on a binary
// little-endian PLY of double x y z (as scangen writes); writes the mesh as
// an ASCII PLY for `scanmesh eval` and prints the reconstruction's time
// alone. Built by tools/cgal_afsr.sh; not part of CI.
//
//   cgal_afsr d1m.ply afsr.ply && scanmesh eval afsr.ply --reference dragon.ply
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <array>
#include <chrono>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>
typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 P;
int main(int argc, char** argv) {
  if (argc < 3) { std::cerr << "usage: cgal_afsr in.ply out.ply\n"; return 2; }
  std::ifstream in(argv[1], std::ios::binary);
  if (!in) { std::cerr << argv[1] << ": cannot open\n"; return 1; }
  std::string line; size_t n = 0;
  while (std::getline(in, line) && line != "end_header")
    if (line.rfind("element vertex", 0) == 0) n = std::stoull(line.substr(15));
  std::vector<double> xyz(3 * n);
  in.read(reinterpret_cast<char*>(xyz.data()), xyz.size() * sizeof(double));
  std::vector<P> pts; pts.reserve(n);
  for (size_t i = 0; i < n; ++i) pts.emplace_back(xyz[3*i], xyz[3*i+1], xyz[3*i+2]);
  std::vector<std::array<std::size_t, 3>> faces;
  auto t0 = std::chrono::steady_clock::now();
  CGAL::advancing_front_surface_reconstruction(pts.begin(), pts.end(), std::back_inserter(faces));
  double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ofstream out(argv[2]);
  out << "ply\nformat ascii 1.0\nelement vertex " << n << "\nproperty double x\nproperty double y\nproperty double z\nelement face " << faces.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  out.precision(17);
  for (auto& p : pts) out << p.x() << " " << p.y() << " " << p.z() << "\n";
  for (auto& f : faces) out << "3 " << f[0] << " " << f[1] << " " << f[2] << "\n";
  std::cerr << "afsr: " << faces.size() << " faces in " << s << " s\n";
}
