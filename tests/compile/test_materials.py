"""The material rows `compile_scene` writes (compile/__init__.py's `_Materials`): a metal's physical columns, and
the classic coefficients the local methods read for it."""

import numpy as np
import pytest

import lumos
from lumos.compile import compile_scene
from lumos.compile.emitters import physical_materials
from lumos.kernels import layout as L
from lumos.scene.materials import METALS, phong_exponent


def rows_of(*materials):
    scene = lumos.load_scene({"objects": [{"type": "sphere", "center": [3 * i, 0, 0], "material": m}
                                          for i, m in enumerate(materials)]})
    return compile_scene(scene).arrays.materials


def test_a_metal_carries_its_index_width_and_tint_and_reads_classically_as_its_head_on_reflectance():
    eta, k = METALS["Cu"]
    f0 = [((e - 1) ** 2 + kk * kk) / ((e + 1) ** 2 + kk * kk) for e, kk in zip(eta, k)]
    smooth, rough = rows_of({"conductor": {"metal": "Cu"}}, {"conductor": {"metal": "Cu", "alpha": [0.2, 0.4]}})
    for row in (smooth, rough):
        assert row[L.MAT_MODEL] == L.MODEL_CONDUCTOR
        np.testing.assert_allclose(row[L.MAT_ETA:L.MAT_ETA + 3], eta)
        np.testing.assert_allclose(row[L.MAT_K:L.MAT_K + 3], k)
        np.testing.assert_allclose(row[L.MAT_KA:L.MAT_KA + 3], f0)
        np.testing.assert_array_equal(row[L.MAT_KD:L.MAT_KD + 3], 0.0)
    np.testing.assert_allclose(smooth[L.MAT_KR:L.MAT_KR + 3], f0)  # a mirror for whitted
    np.testing.assert_array_equal(smooth[L.MAT_KS:L.MAT_KS + 3], 0.0)
    np.testing.assert_allclose(rough[L.MAT_KS:L.MAT_KS + 3], f0)  # a Phong lobe as wide as the GGX one
    np.testing.assert_array_equal(rough[L.MAT_ALPHA:L.MAT_ALPHA + 2], [0.2, 0.4])
    assert rough[L.MAT_SHININESS] == pytest.approx(phong_exponent(0.3))


def test_classic_coefficients_given_win_and_the_path_tracer_reads_the_metal():
    row = rows_of({"ks": 0.2, "shininess": 50, "conductor": {"metal": "Au", "alpha": 0.3, "tint": 0.8}})[0]
    np.testing.assert_allclose(row[L.MAT_KS:L.MAT_KS + 3], 0.2)
    assert row[L.MAT_SHININESS] == 50
    physical = physical_materials(["gold"], row[None])[0]
    np.testing.assert_allclose(physical[L.MAT_KS:L.MAT_KS + 3], 0.8)  # the microfacet lobe, its tint
    np.testing.assert_array_equal(physical[[L.MAT_KD, L.MAT_KR, L.MAT_KT]], 0.0)
    mirror = physical_materials(["m"], rows_of({"conductor": {"metal": "Au"}}))[0]
    np.testing.assert_allclose(mirror[L.MAT_KR:L.MAT_KR + 3], 1.0)  # α = 0: the mirror lobe, weighted by F
    np.testing.assert_array_equal(mirror[L.MAT_KS:L.MAT_KS + 3], 0.0)


def test_a_perfect_reflector_is_a_white_mirror_and_classic_materials_stay_classic():
    perfect, plain = rows_of({"conductor": {}}, {"kd": 0.5})
    np.testing.assert_allclose(perfect[L.MAT_KR:L.MAT_KR + 3], 1.0)
    np.testing.assert_array_equal(perfect[L.MAT_ETA:L.MAT_K + 3], 0.0)  # η = k = 0: F = 1
    assert plain[L.MAT_MODEL] == L.MODEL_CLASSIC


def test_a_plastic_keeps_its_base_carries_its_coat_tables_and_reads_classically_as_its_coat():
    from lumos.compile.plastic import coat_tables

    smooth, rough = rows_of({"kd": [0.5, 0.2, 0.1], "plastic": {"ior": 1.5}},
                            {"kd": [0.5, 0.2, 0.1], "plastic": {"alpha": 0.3, "ior": 1.5}})
    f0 = ((1.5 - 1) / (1.5 + 1)) ** 2
    for row, alpha in ((smooth, 0.0), (rough, 0.3)):
        assert row[L.MAT_MODEL] == L.MODEL_PLASTIC and row[L.MAT_ETA] == 1.5
        t, fdr = coat_tables(alpha, 1.5)
        np.testing.assert_array_equal(row[L.MAT_COAT:L.MAT_COAT + L.MAT_COAT_SIZE], t)
        assert row[L.MAT_FDR] == fdr
        assert 0.0 < t.min() and t.max() < 1.0 and 0.0 < fdr < 1.0
    np.testing.assert_allclose(smooth[L.MAT_KR:L.MAT_KR + 3], f0)
    np.testing.assert_allclose(rough[L.MAT_KS:L.MAT_KS + 3], f0)
    np.testing.assert_allclose(rough[L.MAT_KD:L.MAT_KD + 3], [0.5, 0.2, 0.1])
    physical = physical_materials(["p"], rough[None])[0]  # the base stays, the coat's lobe is ks = tint, no scaling
    np.testing.assert_allclose(physical[L.MAT_KD:L.MAT_KD + 3], [0.5, 0.2, 0.1])
    np.testing.assert_allclose(physical[L.MAT_KS:L.MAT_KS + 3], 1.0)


def test_a_material_is_a_metal_or_a_plastic_not_both():
    with pytest.raises(lumos.LumosError, match="give one of conductor, plastic, dielectric, principled, not "
                                               "conductor and "
                                               "plastic"):
        rows_of({"conductor": {}, "plastic": {}})


def test_glass_carries_its_relative_index_widths_and_tints_and_reads_classically_as_kt_ior_glass():
    smooth, rough = rows_of({"dielectric": {"ior": 1.5, "ext_ior": 1.2, "transmit_tint": [0.9, 0.8, 0.7]}},
                            {"dielectric": {"ior": 1.5, "alpha": [0.1, 0.3], "tint": 0.5}})
    for row in (smooth, rough):
        assert row[L.MAT_MODEL] == L.MODEL_DIELECTRIC and row[L.MAT_FRESNEL] == 1.0
        np.testing.assert_array_equal(row[L.MAT_KD:L.MAT_KD + 3], 0.0)
    assert smooth[L.MAT_ETA] == smooth[L.MAT_IOR] == pytest.approx(1.25)  # local methods: the relative index
    np.testing.assert_allclose(smooth[L.MAT_KT:L.MAT_KT + 3], [0.9, 0.8, 0.7])
    np.testing.assert_allclose(smooth[L.MAT_TINT_T:L.MAT_TINT_T + 3], [0.9, 0.8, 0.7])
    np.testing.assert_array_equal(smooth[L.MAT_KS:L.MAT_KS + 3], 0.0)
    np.testing.assert_allclose(rough[L.MAT_KS:L.MAT_KS + 3], 0.5 * 0.04)  # a highlight of F0, as wide as GGX
    assert rough[L.MAT_SHININESS] == pytest.approx(phong_exponent(0.2))
    np.testing.assert_array_equal(rough[L.MAT_ALPHA:L.MAT_ALPHA + 2], [0.1, 0.3])
    np.testing.assert_allclose(rough[L.MAT_TINT:L.MAT_TINT + 3], 0.5)
    p_smooth, p_rough = physical_materials(["s", "r"], np.stack([smooth, rough]))  # one lobe of weight 1
    np.testing.assert_array_equal(p_smooth[[L.MAT_KD, L.MAT_KS, L.MAT_KR, L.MAT_KT]], [0.0, 0.0, 0.0, 1.0])
    np.testing.assert_array_equal(p_rough[[L.MAT_KD, L.MAT_KS, L.MAT_KR, L.MAT_KT]], [0.0, 1.0, 0.0, 0.0])
    with pytest.raises(lumos.LumosError, match="ior must differ from ext_ior"):
        rows_of({"dielectric": {"ior": 1.3, "ext_ior": 1.3}})
