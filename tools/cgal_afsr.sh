#!/bin/sh
# Builds the CGAL advancing-front peer of the projection bench (needs
# libcgal-dev, libgmp-dev).
set -e
cd "$(dirname "$0")"
g++ -O2 -DNDEBUG -DCGAL_NDEBUG -o "${1:-/tmp/cgal_afsr}" cgal_afsr.cpp -lgmp -lmpfr
