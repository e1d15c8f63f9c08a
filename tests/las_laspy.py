"""laspy's side of tests/las_laspy.rs: an independent reader (and writer)
for LAS files scanmesh writes.

    las_laspy.py gen DIR            write the synthetic matrix into DIR
    las_laspy.py check              for each line IN<tab>OUT<tab>N of stdin,
                                    check OUT against IN; N=1: OUT gained
                                    normals and flags as extra bytes;
                                    N=REF.ply: OUT gained the curvature
                                    REF holds (k1 k2 H K residual, flags)
    las_laspy.py pcd PCD REF.ply    check a binary PCD against a PLY, both
                                    read here with numpy, field by field,
                                    bit for bit
    las_laspy.py drop IN ALL CLEAN  check that CLEAN (outliers --drop) holds
                                    IN's records where ALL (outliers) has no
                                    outlier flag, in order, every dimension

`gen` writes LAS 1.2 (point formats 0-3), 1.3 (0-5) and 1.4 (0-10) with
every field over its legal range as laspy reads it: return numbers 0-7 in
formats 0-5 (3 bits), 0-15 in 6-10; classes 0-31 in 0-5 (5 bits), 0-255 in
6-10; two described extra bytes fields, a CRS VLR (GeoTIFF keys, or WKT
in LAS 1.4) and in LAS 1.4 an EVLR. `check` exits non-zero naming the
file and its first difference."""

import sys

import numpy as np
import laspy
from laspy.vlrs.vlrlist import VLRList

SIDE = 20


def matrix():
    for f in range(4):
        yield "1.2", f
    for f in range(6):
        yield "1.3", f
    for f in range(11):
        yield "1.4", f


def geotiff_vlr():
    keys = np.array([1, 1, 0, 1, 3072, 0, 1, 26910], dtype="<u2").tobytes()
    return laspy.VLR("LASF_Projection", 34735, "GeoTIFF GeoKeyDirectoryTag", keys)


def wkt_vlr():
    wkt = b'PROJCS["NAD83 / UTM zone 10N",GEOGCS["NAD83"],UNIT["metre",1]]\0'
    return laspy.VLR("LASF_Projection", 2112, "OGC WKT", wkt)


def gen(out_dir):
    rng = np.random.default_rng(38)
    for version, fmt in matrix():
        header = laspy.LasHeader(point_format=fmt, version=version)
        header.scales = np.array([0.001, 0.001, 0.0025])
        header.offsets = np.array([512000.0, 5403000.0, -10.0])
        header.add_extra_dims(
            [
                laspy.ExtraBytesParams("amp", np.uint8, description="amplitude"),
                laspy.ExtraBytesParams("dev", np.int16, description="deviation"),
            ]
        )
        if version == "1.4":
            header.vlrs.append(wkt_vlr())
            header.global_encoding.wkt = True
            evlr = laspy.VLR("test_user", 77, "an EVLR kept whole", bytes(range(256)) * 2)
            header.evlrs = VLRList([evlr])
        else:
            header.vlrs.append(geotiff_vlr())
        n = SIDE * SIDE
        las = laspy.LasData(header)
        u = np.arange(n) % SIDE
        v = np.arange(n) // SIDE
        las.x = 512000.0 + 0.25 * u
        las.y = 5403000.0 + 0.25 * v
        las.z = 0.02 * np.hypot(u, v) + 0.0025 * rng.integers(0, 5, n)
        extended = fmt >= 6
        returns = 16 if extended else 8
        classes = 256 if extended else 32
        las.intensity = rng.integers(0, 65536, n, dtype=np.uint16)
        las.return_number = rng.integers(0, returns, n)
        las.number_of_returns = rng.integers(0, returns, n)
        las.classification = rng.integers(0, classes, n)
        las.synthetic = rng.integers(0, 2, n).astype(bool)
        las.key_point = rng.integers(0, 2, n).astype(bool)
        las.withheld = rng.integers(0, 2, n).astype(bool)
        las.scan_direction_flag = rng.integers(0, 2, n).astype(bool)
        las.edge_of_flight_line = rng.integers(0, 2, n).astype(bool)
        las.user_data = rng.integers(0, 256, n, dtype=np.uint8)
        las.point_source_id = rng.integers(0, 65536, n, dtype=np.uint16)
        if extended:
            las.overlap = rng.integers(0, 2, n).astype(bool)
            las.scanner_channel = rng.integers(0, 4, n)
            las.scan_angle = rng.integers(-30000, 30001, n, dtype=np.int16)
        else:
            las.scan_angle_rank = rng.integers(-90, 91, n, dtype=np.int8)
        dims = set(las.point_format.dimension_names)
        if "gps_time" in dims:
            las.gps_time = 3.0e8 + rng.random(n) * 100.0
        if "red" in dims:
            for c in ("red", "green", "blue"):
                las[c] = rng.integers(0, 65536, n, dtype=np.uint16)
        if "nir" in dims:
            las.nir = rng.integers(0, 65536, n, dtype=np.uint16)
        if "wavepacket_index" in dims:
            las.wavepacket_index = rng.integers(0, 256, n, dtype=np.uint8)
            las.wavepacket_offset = rng.integers(0, 1 << 40, n, dtype=np.uint64)
            las.wavepacket_size = rng.integers(0, 1 << 32, n, dtype=np.uint32)
            las.return_point_wave_location = rng.random(n).astype(np.float32)
            las.x_t = rng.random(n).astype(np.float32)
            las.y_t = rng.random(n).astype(np.float32)
            las.z_t = rng.random(n).astype(np.float32)
        las.amp = rng.integers(0, 256, n, dtype=np.uint8)
        las.dev = rng.integers(-32768, 32768, n, dtype=np.int16)
        las.write(f"{out_dir}/v{version.replace('.', '')}_f{fmt}.las")


def vlr_bytes(vlr):
    data = vlr.record_data_bytes() if hasattr(vlr, "record_data_bytes") else vlr.record_data
    return (vlr.user_id, vlr.record_id, vlr.description, bytes(data))


CURRENT = [""]


def fail(what):
    print(f"{CURRENT[0]}: {what}")
    sys.exit(1)


NORMALS = ["NormalX", "NormalY", "NormalZ", "scanmesh_flags"]
CURVATURE = ["k1", "k2", "H", "K", "residual"]


def read_ply(path):
    """A binary little-endian PLY of one vertex element, as a numpy record array."""
    types = {"double": "<f8", "float": "<f4", "uchar": "u1", "ushort": "<u2"}
    with open(path, "rb") as f:
        header = []
        while not header or header[-1] != "end_header":
            header.append(f.readline().decode("ascii").strip())
        if "format binary_little_endian 1.0" not in header:
            fail(f"{path}: not binary little-endian PLY")
        n = int(next(h for h in header if h.startswith("element vertex")).split()[2])
        props = [h.split() for h in header if h.startswith("property")]
        dtype = np.dtype([(p[2], types[p[1]]) for p in props])
        return np.frombuffer(f.read(), dtype=dtype, count=n)


def read_pcd(path):
    """A binary PCD (PCL's format, v0.7), as a numpy record array."""
    with open(path, "rb") as f:
        head = {}
        while True:
            line = f.readline().decode("ascii").strip()
            if line.startswith("#"):
                continue
            key, _, rest = line.partition(" ")
            head[key] = rest.split()
            if key == "DATA":
                break
        if head["DATA"] != ["binary"]:
            fail(f"{path}: DATA {head['DATA']}")
        kinds = {("F", "4"): "<f4", ("F", "8"): "<f8", ("U", "1"): "u1", ("U", "2"): "<u2"}
        dtype = np.dtype(
            [(n, kinds[(t, s)]) for n, s, t in zip(head["FIELDS"], head["SIZE"], head["TYPE"])]
        )
        n = int(head["POINTS"][0])
        if int(head["WIDTH"][0]) * int(head["HEIGHT"][0]) != n:
            fail(f"{path}: WIDTH x HEIGHT is not POINTS")
        return np.frombuffer(f.read(), dtype=dtype, count=n)


def same_bits(a, b):
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and np.array_equal(a.view(f"u{a.itemsize}"), b.view(f"u{b.itemsize}"))


def check_curvature_values(values, ref, flags_name):
    """`values` (by field name) hold `ref`'s curvature bit for bit, and the
    curvature is itself consistent: H the mean and K the product of k1 >=
    k2 wherever no flag is set, NaN wherever one is."""
    for name in CURVATURE:
        if not same_bits(values[name], ref[name]):
            fail(f"{name} differs from the curvature PLY")
    if not np.array_equal(np.asarray(values[flags_name]), ref["flags"]):
        fail("flags differ")
    ok = ref["flags"] == 0
    if ok.sum() == 0:
        fail("no point has curvature")
    k1, k2 = ref["k1"][ok].astype(float), ref["k2"][ok].astype(float)
    scale = np.abs(k1).max() + np.abs(k2).max()
    if (k2 - k1 > 1e-6 * scale).any():
        fail("k1 < k2 somewhere")
    if np.abs(ref["H"][ok] - (k1 + k2) / 2).max() > 1e-4 * scale:
        fail("H is not the mean of k1 and k2")
    if np.abs(ref["K"][ok] - k1 * k2).max() > 1e-4 * scale * scale:
        fail("K is not k1 k2")
    if not np.isnan(ref["k1"][~ok]).all():
        fail("a flagged point has a value")


def check_pcd(pcd, ref_path):
    CURRENT[0] = pcd
    a, ref = read_pcd(pcd), read_ply(ref_path)
    if len(a) != len(ref):
        fail(f"{len(a)} points against {len(ref)}")
    for d in ("x", "y", "z"):
        if not same_bits(a[d], ref[d]):
            fail(f"{d} differs")
    check_curvature_values(a, ref, "flags")
    print(f"ok {pcd}: {len(a)} points")


def check(inp, out, gained):
    CURRENT[0] = out
    extended = gained != "0"
    names = NORMALS if gained == "1" else CURVATURE + ["scanmesh_flags"]
    a, b = laspy.read(inp), laspy.read(out)
    ha, hb = a.header, b.header
    if str(ha.version) != str(hb.version):
        fail(f"version {ha.version} -> {hb.version}")
    if ha.point_format.id != hb.point_format.id:
        fail(f"point format {ha.point_format.id} -> {hb.point_format.id}")
    if not (np.array_equal(ha.scales, hb.scales) and np.array_equal(ha.offsets, hb.offsets)):
        fail(f"scale/offset {ha.scales} {ha.offsets} -> {hb.scales} {hb.offsets}")
    if ha.point_count != hb.point_count:
        fail(f"count {ha.point_count} -> {hb.point_count}")
    for d in ("X", "Y", "Z"):
        if not np.array_equal(np.asarray(a[d]), np.asarray(b[d])):
            fail(f"integer {d} differs")
    for d in a.point_format.dimension_names:
        if not np.array_equal(np.asarray(a[d]), np.asarray(b[d])):
            i = int(np.argmax(np.asarray(a[d]) != np.asarray(b[d])))
            fail(f"{d} differs first at point {i}: {a[d][i]} -> {b[d][i]}")
    # VLRs byte for byte, in order; LASzip's describes the output's own
    # compression, the Extra Bytes VLR may only grow by new descriptors.
    va = [vlr_bytes(v) for v in ha.vlrs if v.user_id != "laszip encoded"]
    vb = [vlr_bytes(v) for v in hb.vlrs if v.user_id != "laszip encoded"]
    eb = ("LASF_Spec", 4)
    grew = extended and not any(v[:2] == eb for v in va)
    if len(vb) != len(va) + int(grew):
        fail(f"VLRs {[v[:2] for v in va]} -> {[v[:2] for v in vb]}")
    for x, y in zip(va, vb):
        if x[:2] == eb and extended:
            if x[:3] != y[:3] or y[3][: len(x[3])] != x[3] or len(y[3]) != len(x[3]) + len(names) * 192:
                fail("Extra Bytes VLR: the input's descriptors are not kept first")
        elif x != y:
            fail(f"VLR {x[:2]} differs")
    ea = [vlr_bytes(v) for v in (ha.evlrs or [])]
    ebs = [vlr_bytes(v) for v in (hb.evlrs or [])]
    if ea != ebs:
        fail(f"EVLRs {[v[:2] for v in ea]} -> {[v[:2] for v in ebs]}")
    if extended:
        extra = list(hb.point_format.extra_dimension_names)
        for name in names:
            if name not in extra:
                fail(f"no {name} among {extra}")
    if extended and gained != "1":
        check_curvature_values(b, read_ply(gained), "scanmesh_flags")
    elif extended:
        n = np.stack([b.NormalX, b.NormalY, b.NormalZ], axis=1)
        length = np.linalg.norm(n, axis=1)
        if np.abs(length - 1.0).max() > 1e-5:
            fail(f"normals not unit: {length.min()} .. {length.max()}")
    print(f"ok {out}: {hb.point_count} points, format {hb.point_format.id}, LAS {hb.version}")


def check_drop(inp, full, clean):
    CURRENT[0] = clean
    a, f, c = laspy.read(inp), laspy.read(full), laspy.read(clean)
    kept = np.asarray(f.scanmesh_flags) & 1 == 0
    if kept.all() or not kept.any():
        fail(f"{kept.sum()} of {len(kept)} kept: nothing tells the drop apart")
    if c.header.point_count != kept.sum():
        fail(f"{c.header.point_count} records, {kept.sum()} kept")
    for d in a.point_format.dimension_names:
        if not np.array_equal(np.asarray(a[d])[kept], np.asarray(c[d])):
            fail(f"{d} differs from the input's kept records")
    if not same_bits(np.asarray(f.outlier_score)[kept], np.asarray(c.outlier_score)):
        fail("outlier_score differs from the full output's")
    print(f"ok {clean}: {c.header.point_count} of {len(kept)} records kept")


if __name__ == "__main__":
    if sys.argv[1] == "gen":
        gen(sys.argv[2])
    elif sys.argv[1] == "drop":
        check_drop(sys.argv[2], sys.argv[3], sys.argv[4])
    elif sys.argv[1] == "pcd":
        check_pcd(sys.argv[2], sys.argv[3])
    else:
        for line in sys.stdin:
            if line.strip():
                inp, out, n = line.rstrip("\n").split("\t")
                check(inp, out, n)
