"""Hostile OBJ + MTL files: random and corrupted text given to `lumos.io.obj.import_obj` gives an ImportedModel
whose meshes are well formed, or a one-line LumosError, never another exception (property-based, hypothesis)."""

import tempfile
from pathlib import Path

import pytest

hypothesis = pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from lumos.errors import LumosError  # noqa: E402
from lumos.io.obj import import_obj  # noqa: E402
from helpers import check_pieces  # noqa: E402

NUM = st.one_of(st.integers(-12, 12).map(str), st.floats(-3, 3, allow_nan=False).map(lambda x: f"{x:.3g}"),
                st.sampled_from(["nan", "inf", "-inf", "1e309", "1e300", "-0", "x", "", "1.#IND", "0x1", "1e-320"]))
INDEX = st.one_of(st.integers(-6, 9).map(str), st.sampled_from(["", "a", "99999999999999999999", "1.5"]))
CORNER = st.tuples(INDEX, st.sampled_from(["", "/", "//"]), INDEX, st.sampled_from(["", "/"]), INDEX).map("".join)
OBJ_LINE = st.one_of(
    st.lists(NUM, min_size=0, max_size=7).map(lambda xs: "v " + " ".join(xs)),
    st.lists(NUM, min_size=0, max_size=3).map(lambda xs: "vt " + " ".join(xs)),
    st.lists(NUM, min_size=0, max_size=4).map(lambda xs: "vn " + " ".join(xs)),
    st.lists(CORNER, min_size=0, max_size=7).map(lambda xs: "f " + " ".join(xs)),
    st.sampled_from(["s off", "s 0", "s 1", "s 2", "s", "s -1", "s 99999999999", "g a b", "o thing", "g",
                     "usemtl m", "usemtl ghost", "usemtl", "mtllib m.mtl", "mtllib none.mtl", "l 1 2", "p 1",
                     "curv 0 1 1 2", "# c", "\\", "v 1 2 3 \\", "\r", "\t", "\x00", "é"]),
    st.text(max_size=12),
)
MTL_LINE = st.one_of(
    st.tuples(st.sampled_from(["Ka", "Kd", "Ks", "Ke", "Tf", "Ns", "Ni", "d", "Tr", "illum"]),
              st.lists(NUM, min_size=0, max_size=3)).map(lambda t: t[0] + " " + " ".join(t[1])),
    st.tuples(st.sampled_from(["map_Kd", "map_Ks", "map_d", "bump", "map_bump", "norm"]),
              st.lists(st.sampled_from(["-s", "-o", "-bm", "-clamp", "on", "-mm", "-type", "t.png", "nope.png",
                                        "1", "0", "-1", "x"]), max_size=5)).map(lambda t: t[0] + " " + " ".join(t[1])),
    st.sampled_from(["newmtl m", "newmtl", "newmtl n", "illum 4", "illum 11", "Tf spectral f.rfl"]),
    st.text(max_size=12),
)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(obj=st.lists(OBJ_LINE, max_size=25), mtl=st.lists(MTL_LINE, max_size=12),
       base=st.booleans())
def test_random_and_corrupted_files_import_or_fail_in_one_line(obj, mtl, base):
    lines = (["mtllib m.mtl", "v 0 0 0", "v 1 0 0", "v 0 1 0", "vt 0 0", "vn 0 0 1"] if base else []) + obj
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        (folder / "m.mtl").write_text("newmtl m\n" + "\n".join(mtl), encoding="utf-8", errors="surrogatepass")
        (folder / "t.png").write_bytes(b"")
        path = folder / "r.obj"
        path.write_bytes("\n".join(lines).encode("utf-8", "surrogatepass"))
        try:
            model = import_obj(path)
        except LumosError as exc:
            assert "\n" not in str(exc) and str(exc)
            return
        check_pieces(model)
        assert all("\n" not in w for w in model.warnings)
