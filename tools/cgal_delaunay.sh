#!/bin/sh
# Builds the CGAL peer of the 3-D Delaunay bench (needs libcgal-dev, libgmp-dev).
set -e
cd "$(dirname "$0")"
g++ -O3 -DNDEBUG -DCGAL_NDEBUG -o "${1:-/tmp/cgal_delaunay}" cgal_delaunay.cpp -lgmp -lmpfr
