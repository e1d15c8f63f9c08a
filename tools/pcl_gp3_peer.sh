#!/bin/sh
# PCL's greedy projection triangulation on a PLY point file, for the
# side-by-side with `reconstruct --method projection` (issue 14): PLY ->
# PCD, normals from the 12 nearest neighbours, then GP3 with a search
# radius of 8 mean spacings and mu 2.5 (PCL's tutorial values, scaled).
# Prints each stage's CPU seconds. Not run in CI (needs pcl-tools).
# Usage: tools/pcl_gp3_peer.sh input.ply spacing workdir
set -eu
in=$1; sp=$2; dir=$3
mkdir -p "$dir"
pcl_ply2pcd "$in" "$dir/in.pcd" > /dev/null
/usr/bin/time -f "pcl normal estimation: %U user %S sys %e wall %M KB" \
    pcl_normal_estimation "$dir/in.pcd" "$dir/normals.pcd" -k 12 > /dev/null
radius=$(python3 -c "print(8 * $sp)")
/usr/bin/time -f "pcl gp3: %U user %S sys %e wall %M KB" \
    pcl_gp3_surface "$dir/normals.pcd" "$dir/gp3.vtk" -radius "$radius" -mu 2.5 > /dev/null
