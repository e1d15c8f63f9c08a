// Peer for the 3-D Delaunay bench (issue 18): CGAL's Delaunay_triangulation_3
// on a binary little-endian PLY of double x y z (as scangen writes), timing
// the triangulation alone (range insert: CGAL's spatial sort + insertion).
// Built by tools/cgal_delaunay.sh; not part of CI.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Delaunay_triangulation_3.h>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>
typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Delaunay_triangulation_3<K> DT;
int main(int argc, char** argv) {
  if (argc < 2) { std::cerr << "usage: cgal_delaunay file.ply\n"; return 2; }
  std::ifstream in(argv[1], std::ios::binary);
  std::string line; size_t n = 0;
  while (std::getline(in, line) && line != "end_header")
    if (line.rfind("element vertex", 0) == 0) n = std::stoull(line.substr(15));
  std::vector<double> xyz(3 * n);
  in.read(reinterpret_cast<char*>(xyz.data()), xyz.size() * sizeof(double));
  std::vector<K::Point_3> pts; pts.reserve(n);
  for (size_t i = 0; i < n; ++i) pts.emplace_back(xyz[3*i], xyz[3*i+1], xyz[3*i+2]);
  std::vector<double>().swap(xyz);
  auto t0 = std::chrono::steady_clock::now();
  DT dt(pts.begin(), pts.end());
  double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ifstream st("/proc/self/status"); std::string hwm;
  while (std::getline(st, line)) if (line.rfind("VmHWM", 0) == 0) hwm = line;
  std::printf("cgal: %zu points, %zu vertices, %zu finite cells, triangulation %.3f s, %s\n",
              n, dt.number_of_vertices(), dt.number_of_finite_cells(), s, hwm.c_str());
  return 0;
}
