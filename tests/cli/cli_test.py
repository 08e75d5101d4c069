#!/usr/bin/env python3
"""CLI tests of the `vkas` tool (tests/cli/CMakeLists.txt runs one case per ctest test).

Every case runs the tool on real files and checks what it printed or wrote against facts computed here: triangle
counts and bounds parsed from the OBJ, the size-query formula of docs/FORMAT.md, PNG sizes and pixels decoded with
zlib, the heatmap's statistics recomputed from its per-pixel counts. Standard library only. Exit 0 pass, 1 fail,
77 skip."""
import argparse, concurrent.futures, json, os, random, shutil, struct, subprocess, sys, time, zlib

GLMARK = "/usr/share/glmark2/models"
ASSIMP = "/usr/share/assimp/models"
BUNNY = f"{GLMARK}/bunny.obj"
A = None  # parsed arguments


class Fail(Exception):
    pass


def need(path):
    if not os.path.exists(path):
        raise Fail(f"{path} is missing: run scripts/setup-deps.sh (glmark2-data, assimp-testmodels)")
    return path


def expect(cond, what):
    if not cond:
        raise Fail(what)


def run(*args, ok=True, timeout=60):
    t0 = time.time()
    p = subprocess.run([A.tool, *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout,
                       text=True)
    dt = time.time() - t0
    print(f"$ vkas {' '.join(map(str, args))}  -> {p.returncode} ({dt:.2f} s)")
    if ok and p.returncode != 0:
        raise Fail(f"exit status {p.returncode}\n{p.stdout}\n{p.stderr}")
    return p


def work(name):
    os.makedirs(A.work, exist_ok=True)
    return os.path.join(A.work, name)


def png(path):
    """(width, height, rows of RGB bytes) of an 8-bit RGB PNG, decoded with zlib."""
    data = open(path, "rb").read()
    expect(data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG")
    pos, idat, w, h = 8, b"", 0, 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, colour = struct.unpack(">IIBB", body[:10])
            expect(depth == 8 and colour == 2, f"{path}: not 8-bit RGB")
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw, stride, rows, prev = zlib.decompress(idat), 3 * w, [], bytearray(3 * w)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a, b, c = line[i - 3] if i >= 3 else 0, prev[i], prev[i - 3] if i >= 3 else 0
            if f == 1: line[i] = (line[i] + a) & 255
            elif f == 2: line[i] = (line[i] + b) & 255
            elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return w, h, rows


def check_image(path, w, h, min_colours=16):
    pw, ph, rows = png(path)
    expect((pw, ph) == (w, h), f"{path} is {pw}x{ph}, expected {w}x{h}")
    colours = {r[i:i + 3] for r in rows for i in range(0, len(r), 3)}
    expect(len(colours) >= min_colours, f"{path} has only {len(colours)} colours: trivial content")
    return rows


def obj_facts(path):
    """Triangles (faces fanned) and float32 bounds of an OBJ's vertices."""
    f32 = lambda x: struct.unpack("f", struct.pack("f", x))[0]
    lo, hi, tris = [float("inf")] * 3, [float("-inf")] * 3, 0
    for line in open(path):
        w = line.split()
        if not w: continue
        if w[0] == "v":
            for k in range(3):
                v = f32(float(w[1 + k]))
                lo[k], hi[k] = min(lo[k], v), max(hi[k], v)
        elif w[0] == "f":
            tris += len(w) - 3
    return tris, lo, hi


def size_query(n, g, fragments=False):
    """docs/FORMAT.md, "Build sizes": accelerationStructureSize of n triangles in g geometries; fragments: a build
    that may cut triangles (PREFER_FAST_TRACE), with room for floor(n / 4) cuts from 64 triangles on."""
    a64 = lambda v: (v + 63) // 64 * 64
    a16 = lambda v: (v + 15) // 16 * 16
    cuts = n // 4 if fragments and n >= 64 else 0
    records = n + cuts
    nodes = 0 if records <= 4 else records // 5 + (records - 1) // 7 + 1
    size = a64(a64(256 + 32 * g) + 256 * nodes) + 44 * records + (4 if records else 0)
    return a16(size) + 64 * cuts if cuts else size


def check_tree_consistency(j):
    h, t, b = j["header"], j["tree"], j["bytes"]
    expect(sum(b.values()) == h["usedSize"], f"bytes by part {b} do not add up to usedSize {h['usedSize']}")
    expect(j["sizes"]["compacted"] == h["usedSize"], "compacted size != usedSize")
    expect(t["internalNodes"] == h["nodeCount"], "walked nodes != nodeCount")
    expect(sum(i * n for i, n in enumerate(t["leafSizes"])) == t["references"] == h["recordCount"],
           "leaf sizes do not add up to the records")
    expect(sum(t["childrenPerNode"]) == t["internalNodes"] and sum(t["leavesAtDepth"]) == t["leaves"],
           "histograms do not add up")
    expect(sum(t["nodesAtDepth"]) == t["internalNodes"], "node depth histogram does not add up")
    expect(0 < t["nodeFill"] <= 1 and t["sahCost"] > 0, "node fill or SAH cost out of range")


# ---- cases ---------------------------------------------------------------------------------------------------------

def case_help():
    out = run("--help").stdout
    for cmd in ("render", "inspect", "heatmap", "bench", "info"):
        expect(cmd in out, f"--help does not list {cmd}")
        run(cmd, "--help")


def case_render_builtin():
    out = work("builtin.png")
    run("render", "--width", 64, "--height", 48, "--spp", 1, "--instances", 50, "-o", out)
    check_image(out, 64, 48)


def case_render_bunny_deterministic():
    need(BUNNY)
    images = []
    for threads in (1, 2, 1):
        out = work(f"bunny-{threads}-{len(images)}.png")
        run("render", BUNNY, "--width", 64, "--height", 48, "--spp", 2, "--threads", threads, "-o", out)
        images.append(open(out, "rb").read())
    check_image(out, 64, 48)
    expect(images[0] == images[1] == images[2], "the image differs across runs or thread counts")


def case_render_formats():
    files = [f"{GLMARK}/horse.3ds", f"{GLMARK}/cat.3ds", f"{ASSIMP}/OFF/Wuson.off", f"{ASSIMP}/PLY/Wuson.ply",
             f"{ASSIMP}/STL/Spider_binary.stl", f"{ASSIMP}/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb"]
    for f in files:
        need(f)
        out = work(os.path.basename(f) + ".png")
        p = run("render", f, "--width", 48, "--height", 36, "--spp", 1, "-o", out)
        expect("triangles" in p.stdout, f"no triangle count printed for {f}")
        check_image(out, 48, 36)


def case_render_gltf():
    need(BUNNY)
    gltf = work("bunny.gltf")
    subprocess.run([A.export_gltf, BUNNY, gltf], check=True)
    out = work("bunny-gltf.png")
    run("render", gltf, "--width", 48, "--height", 36, "--spp", 1, "-o", out)
    check_image(out, 48, 36)
    j = json.loads(run("inspect", gltf, "--json").stdout)
    tris, lo, hi = obj_facts(BUNNY)
    expect(j["mesh"]["triangles"] == tris, f"glTF round trip: {j['mesh']['triangles']} triangles, OBJ has {tris}")


def case_inspect_bunny_json():
    need(BUNNY)
    tris, lo, hi = obj_facts(BUNNY)
    for pref in ("default", "fast-trace", "fast-build"):
        j = json.loads(run("inspect", BUNNY, "--json", "--preference", pref).stdout)
        h = j["header"]
        expect(j["mesh"]["triangles"] == tris == h["primitiveCount"], f"{pref}: triangles {h['primitiveCount']}, OBJ {tris}")
        f32 = lambda v: [struct.unpack("f", struct.pack("f", x))[0] for x in v]  # JSON has 9 digits: a float exactly
        expect(f32(h["boundsLower"]) == lo and f32(h["boundsUpper"]) == hi, f"{pref}: bounds {h['boundsLower']} {h['boundsUpper']} != OBJ {lo} {hi}")
        formula = size_query(tris, h["geometryCount"], fragments=pref == "fast-trace")
        expect(j["sizes"]["accelerationStructureSize"] == formula,
               f"{pref}: size {j['sizes']['accelerationStructureSize']} != formula {formula}")
        expect(h["recordCount"] <= tris + (tris // 4 if pref == "fast-trace" else 0),
               f"{pref}: {h['recordCount']} records for {tris} triangles")
        expect(h["version"] == 2 and h["type"] == "bottom level" and h["primitiveType"] == "triangles", "header fields")
        check_tree_consistency(j)
    text = run("inspect", BUNNY).stdout
    for word in ("block format 2", "SAH cost", "leaf depth", "leaf size", "compacted", "node fill"):
        expect(word in text, f"text report lacks {word!r}")


def case_inspect_blob_roundtrip():
    need(BUNNY)
    blob = work("bunny.bin")
    built = json.loads(run("inspect", BUNNY, "--json", "--write-blob", blob).stdout)
    loaded = json.loads(run("inspect", blob, "--json").stdout)
    expect(loaded["serialized"]["integrity"] == "passed" and loaded["serialized"]["layout"] == 2, "integrity verdict")
    expect(loaded["serialized"]["fileSize"] == os.path.getsize(blob) == built["sizes"]["serialization"], "blob size")
    for part in ("header", "bytes", "tree"):
        expect(loaded[part] == built[part], f"the loaded blob's {part} differs from the built structure's")


def case_inspect_boxes():
    need(BUNNY)
    out = work("boxes.obj")
    j = json.loads(run("inspect", BUNNY, "--json", "--boxes", 0, out).stdout)
    lines = open(out).read().split("\n")
    verts = [list(map(float, l.split()[1:])) for l in lines if l.startswith("v ")]
    faces = [l for l in lines if l.startswith("f ")]
    n = j["boxes"]["count"]
    expect(n >= 2 and len(verts) == 8 * n and len(faces) == 6 * n, f"{n} boxes, {len(verts)} vertices, {len(faces)} faces")
    lo, hi = j["header"]["boundsLower"], j["header"]["boundsUpper"]
    expect(all(lo[k] <= v[k] <= hi[k] for v in verts for k in range(3)), "a box lies outside the structure's bounds")
    deep = j["tree"]["nodesAtDepth"]
    expect(len(deep) > 1 and n == sum(1 for _ in range(n)), "tree depth")
    bad = run("inspect", BUNNY, "--boxes", "x", out, ok=False)
    expect(bad.returncode != 0 and "level" in bad.stderr, "--boxes with a bad level")


def case_inspect_top_level_blob():
    blob = need(os.path.join(A.source, "tests/data/serialized_format2_tlas.bin"))
    j = json.loads(run("inspect", blob, "--json").stdout)
    expect(j["header"]["type"] == "top level" and j["header"]["primitiveType"] == "instances", "top-level header")
    expect(j["serialized"]["handleCount"] == 4 and j["bytes"]["instances"] == 128 * j["header"]["recordCount"], "instances")
    check_tree_consistency(j)


def heatmap(args, name):
    counts = work(name + ".counts")
    out = work(name + ".png")
    j = json.loads(run("heatmap", *args, "--json", "--counts", counts, "-o", out).stdout)
    rows = [list(map(int, l.split())) for l in open(counts) if not l.startswith("#")]
    return j, rows, out, counts


def case_heatmap_stats():
    need(BUNNY)
    j, rows, out, counts = heatmap([BUNNY, "--width", 64, "--height", 48, "--threads", 1], "heat1")
    expect(len(rows) == 64 * 48 == j["pixels"], "one count line per pixel")
    for k, key in enumerate(("nodes", "primitives", "instances")):
        col = [r[k] for r in rows]
        s = j[key]
        expect(s["min"] == min(col) and s["max"] == max(col) and s["total"] == sum(col), f"{key}: {s} vs counts")
        expect(abs(s["mean"] - sum(col) / len(col)) < 1e-6, f"{key} mean")
    expect(j["agreement"]["agree"] == j["pixels"], f"counting traversal disagrees with vkasTraceRays: {j['agreement']}")
    expect(j["agreement"]["vkasHits"] > 0 and j["nodes"]["max"] > j["nodes"]["min"], "the bunny is in view")
    check_image(out, 64, 48, 4)
    j2, _, out2, counts2 = heatmap([BUNNY, "--width", 64, "--height", 48, "--threads", 2], "heat2")
    expect(open(out, "rb").read() == open(out2, "rb").read() and open(counts).read() == open(counts2).read(),
           "heatmap differs across thread counts")
    p = run("render", BUNNY, "--heatmap", "--metric", "primitives", "--width", 32, "--height", 24, "-o", work("rh.png"))
    expect("triangles tested per ray" in p.stdout and "min" in p.stdout and "mean" in p.stdout, "render --heatmap output")


def write(name, text):
    path = work(name)
    with open(path, "w") as f:
        f.write(text)
    return path


def case_heatmap_one_triangle():
    # A structure of one triangle has no internal node (the root is a leaf), and the top level of one instance
    # neither: every ray tests exactly one instance and one triangle and visits no node.
    tri = write("one.obj", "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n")
    j, rows, _, _ = heatmap([tri, "--width", 32, "--height", 24], "one")
    expect(all(r == [0, 1, 1] for r in rows), f"counts of a one-triangle scene: {set(map(tuple, rows))}")
    expect(j["agreement"]["agree"] == j["pixels"] and j["agreement"]["vkasHits"] > 0, "hits")


def case_heatmap_cube():
    # 12 triangles: a few leaves under one root node (inspect tells their sizes). Every ray visits that node and no
    # other, and tests whole leaves: its triangle count is a sum of some of the leaf sizes, at most 12.
    cube = need(f"{ASSIMP}/OFF/Cube.off")
    j, rows, _, _ = heatmap([cube, "--width", 32, "--height", 24], "cube")
    insp = json.loads(run("inspect", cube, "--json").stdout)
    expect(insp["header"]["nodeCount"] == 1 and insp["tree"]["references"] == 12, f"cube tree: {insp['tree']}")
    sizes = [n for n, count in enumerate(insp["tree"]["leafSizes"]) for _ in range(count)]
    sums = {0}
    for n in sizes:
        sums |= {x + n for x in sums}
    expect(all(r[0] == 1 and r[1] in sums for r in rows), f"counts {set(map(tuple, rows))}, leaf sizes {sizes}")
    expect(j["primitives"]["max"] > 0, "the cube is in view")
    expect(j["agreement"]["agree"] == j["pixels"], "hits")


def case_bench_json():
    horse = need(f"{GLMARK}/horse.3ds")
    args = ["bench", horse, "--rays", 2048, "--reps", 1, "--threads", 2, "--json"]
    if A.sanitized == "1": args.append("--no-embree")
    j = json.loads(run(*args).stdout)
    names = [r["name"] for r in j["rows"]]
    for want in ("build default, 1 thread", "build fast-trace, 2 threads", "build fast-build, 1 thread",
                 "refit, 1 thread", "compaction copy", "camera rays, 1 thread", "diffuse rays, 2 threads",
                 "shadow rays, 2 threads"):
        expect(want in names, f"bench lacks the row {want!r}")
    expect(all(r["vkas"] > 0 for r in j["rows"]), "a measurement is not positive")
    expect(j["triangles"] == json.loads(run("inspect", horse, "--json").stdout)["mesh"]["triangles"], "triangles")


def case_quiet_off_terminal():
    need(BUNNY)
    p = run("render", BUNNY, "--width", 32, "--height", 24, "--spp", 1, "-o", work("q.png"))
    expect(p.stderr == "", f"progress or messages on a non-terminal stderr: {p.stderr!r}")
    p = run("--quiet", "inspect", BUNNY)
    expect(p.stderr == "", "--quiet")


def bad(args, keyword, file_named=None):
    t0 = time.time()
    p = run(*args, ok=False, timeout=30)
    err = p.stderr.strip()
    expect(p.returncode == 1, f"exit status {p.returncode} (expected 1): {err}")
    expect(len(err.splitlines()) == 1, f"not one message: {err!r}")
    expect(keyword in err, f"message lacks {keyword!r}: {err}")
    if file_named: expect(file_named in err, f"message does not name {file_named}: {err}")
    expect("Sanitizer" not in err and "Abort" not in err and time.time() - t0 < 30, "crash or hang")


def both(path, keyword):
    bad(["render", path, "--width", 16, "--height", 12, "-o", work("bad.png")], keyword, path)
    bad(["inspect", path], keyword, path)


def case_bad_missing(): both(work("no-such-file.obj"), "no such file")
def case_bad_directory(): both(A.work, "is a directory")
def case_bad_empty(): both(write("empty.obj", ""), "is empty")
def case_bad_malformed(): both(write("garbage.ply", "ply\nthis is not a ply header\n"), "not a mesh file")
def case_bad_no_triangles(): both(write("lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n"), "no triangles")
def case_bad_nan_vertex(): both(write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"), "not finite")
def case_bad_inf_vertex(): both(write("inf.obj", "v 0 0 0\nv 0 inf 0\nv 0 1 0\nf 1 2 3\n"), "not finite")
def case_bad_huge_header(): both(write("huge.off", "OFF\n2000000000 1000000000 0\n0 0 0\n"), "announces")
# Counts whose byte sizes wrap past 2^64 to a few bytes: still more than the file holds (found by vkas_fuzz_mesh_file).
def case_bad_wrapping_header():
    both(write("wrap.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 6148914691236517206\nproperty float x\n"
               "property float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\n"
               "end_header\n"), "announces")
    both(write("wrap.off", "OFF\n3074457345618258603 0 0\n0 0 0\n"), "announces")
def case_bad_camera(): bad(["render", need(BUNNY), "--camera", "1,2,3", "-o", work("c.png")], "--camera")


def case_bad_unreadable():
    path = write("unreadable.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    os.chmod(path, 0)
    if os.access(path, os.R_OK):
        print("skipped: running as root, every file is readable")
        sys.exit(77)
    both(path, "cannot be read")


def case_bad_index_out_of_range():
    both(write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"), "out of range")
    # OFF: assimp does not check the indices itself; the tool does.
    both(write("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"), "out of range")


def blob():
    need(BUNNY)
    path = work("good.bin")
    if not os.path.exists(path):
        run("inspect", BUNNY, "--write-blob", path)
    return open(path, "rb").read()


def case_bad_truncated_blob():
    data = blob()
    for n in (10, 60, len(data) // 2, len(data) - 1):
        path = work(f"truncated{n}.bin")
        open(path, "wb").write(data[:n])
        bad(["inspect", path], "truncated", path)


def case_bad_corrupted_blob():
    data = bytearray(blob())
    for where in (64 + 8 + 100, len(data) // 2, len(data) - 3):
        c = bytearray(data)
        c[where] ^= 0x5A
        path = work(f"corrupted{where}.bin")
        open(path, "wb").write(c)
        bad(["inspect", path], "integrity", path)
    c = bytearray(data)
    c[40:48] = struct.pack("<Q", 1 << 60)  # a deserialized size larger than the blob
    path = work("badsizes.bin")
    open(path, "wb").write(c)
    bad(["inspect", path], "corrupted", path)


def case_bad_incompatible_blob():
    c = bytearray(blob())
    c[16:32] = b"VKAS-AS-FORMAT-9"
    path = work("incompatible.bin")
    open(path, "wb").write(c)
    bad(["inspect", path], "not loadable", path)


def case_bad_blob_to_render():
    blob()
    bad(["render", work("good.bin"), "-o", work("x.png")], "serialized", "good.bin")


def case_bad_huge_image():
    bad(["render", "--width", 16384, "--height", 16384, "--spp", 1024, "-o", work("big.png")], "memory")


def off_to_binary_ply(path):
    """The OFF file's vertices and faces as a binary little-endian PLY (the form of the truncated-file report)."""
    words = [l.split() for l in open(path) if l.strip() and not l.startswith("#")]
    nv, nf = int(words[1][0]), int(words[1][1])
    body = b"".join(struct.pack("<3f", *map(float, w[:3])) for w in words[2:2 + nv])
    for w in words[2 + nv:2 + nv + nf]:
        n = int(w[0])
        body += struct.pack(f"<B{n}i", n, *map(int, w[1:1 + n]))
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\n"
              f"property float z\nelement face {nf}\nproperty list uchar int vertex_indices\nend_header\n")
    return header.encode() + body


def damaged_sources():
    """(format, extension, bytes) of one test mesh per format docs/CLI.md names."""
    files = [("OBJ", f"{ASSIMP}/OBJ/spider.obj"), ("OBJ polygons", f"{ASSIMP}/OBJ/concave_polygon.obj"),
             ("PLY ASCII", f"{ASSIMP}/PLY/cube_uv.ply"), ("STL ASCII", f"{ASSIMP}/STL/sphereWithHole.stl"),
             ("STL binary", f"{ASSIMP}/STL/Spider_binary.stl"), ("OFF", f"{ASSIMP}/OFF/Wuson.off"),
             ("glTF", f"{ASSIMP}/glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf"),
             ("GLB", f"{ASSIMP}/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb"), ("3DS", f"{GLMARK}/horse.3ds")]
    out = [(fmt, os.path.splitext(f)[1].lower(), open(need(f), "rb").read()) for fmt, f in files]
    out.append(("PLY binary", ".ply", off_to_binary_ply(need(f"{ASSIMP}/OFF/Wuson.off"))))
    return out


def case_bad_damaged_meshes():
    # Each test mesh cut at 20%, 50%, 80% and at random points, and with random bytes flipped; render, inspect and
    # heatmap on each must exit 0 or 1 (then one message naming the file), never die of a signal or hang.
    seed = int(os.environ.get("VKAS_CLI_DAMAGE_SEED", "35"))
    print(f"damage seed {seed} (VKAS_CLI_DAMAGE_SEED=N picks another set of cuts and flips)")
    rng = random.Random(seed)
    inputs = []
    for fmt, ext, data in damaged_sources():
        n = len(data)
        cuts = sorted({n * k // 10 for k in (2, 5, 8)} | {rng.randrange(1, n) for _ in range(4)})
        for c in cuts:
            inputs.append((f"{fmt} cut at {c} of {n} bytes", ext, data[:c]))
        for _ in range(5):
            d = bytearray(data)
            flips = sorted(rng.randrange(n) for _ in range(rng.randint(1, 8)))
            for at in flips:
                d[at] ^= rng.randrange(1, 256)
            inputs.append((f"{fmt} with bytes {flips} flipped", ext, bytes(d)))
    jobs = []
    for i, (what, ext, data) in enumerate(inputs):
        path = work(f"damaged{i}{ext}")
        open(path, "wb").write(data)
        png = work(f"damaged{i}.png")
        jobs += [(what, path, ["render", path, "--width", 32, "--height", 24, "--spp", 1, "-o", png]),
                 (what, path, ["inspect", path]),
                 (what, path, ["heatmap", path, "--width", 32, "--height", 24, "-o", png])]

    def one(job):
        what, path, args = job
        try:
            p = subprocess.run([A.tool, *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=30,
                               text=True, errors="replace")
        except subprocess.TimeoutExpired:
            return f"{what}: `vkas {args[0]}` hung (killed after 30 s)", None
        err = p.stderr.strip()
        if p.returncode < 0:
            return f"{what}: `vkas {args[0]}` died of signal {-p.returncode}: {err[-300:]}", None
        if "Sanitizer" in err or "runtime error" in err:
            return f"{what}: `vkas {args[0]}`: {err[-600:]}", None
        if p.returncode == 1:
            if len(err.splitlines()) != 1 or not err.startswith("vkas: error: ") or path not in err:
                return f"{what}: `vkas {args[0]}` exit 1 without one message naming the file: {err[-300:]!r}", None
        elif p.returncode != 0:
            return f"{what}: `vkas {args[0]}` exit status {p.returncode}: {err[-300:]}", None
        return None, p.returncode

    t0, failures, status = time.time(), [], {0: 0, 1: 0}
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
        for failure, rc in pool.map(one, jobs):
            if failure: failures.append(failure)
            else: status[rc] += 1
    print(f"{len(inputs)} damaged files, {len(jobs)} runs in {time.time() - t0:.1f} s: {status[0]} exit 0, "
          f"{status[1]} exit 1 with a message, {len(failures)} failed")
    expect(not failures, f"{len(failures)} of {len(jobs)} runs failed:\n" + "\n".join(failures[:30]))


def main():
    global A
    ap = argparse.ArgumentParser()
    ap.add_argument("--tool", required=True)
    ap.add_argument("--export-gltf", required=True)
    ap.add_argument("--work", required=True)
    ap.add_argument("--sanitized", default="0")
    ap.add_argument("--source", default=os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
    ap.add_argument("case")
    A = ap.parse_args()
    A.work = os.path.join(A.work, A.case)  # cases run in parallel: one folder each
    shutil.rmtree(A.work, ignore_errors=True)
    t0 = time.time()
    try:
        globals()["case_" + A.case]()
    except Fail as e:
        print(f"FAIL {A.case}: {e}")
        return 1
    print(f"ok {A.case} ({time.time() - t0:.2f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
