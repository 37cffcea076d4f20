"""Figures of the BRDF terms, drawn from the numpy twin (addon/reference/shading.py): PNGs in docs/figures/.

    .venv/bin/python scripts/figures.py

1. fresnel.png: Fresnel reflectance against sin(theta_i) for glass (IOR 1.5), copper and
   aluminium, exact (solid) vs Schlick (eq. 1.11, dashed), spherical-Gaussian Schlick (eq. 1.12,
   dotted) and generalised Schlick (eq. 1.13, dash-dot, p fitted per material); colour strips:
   exact above, Schlick below. The seed's Figure 1.7, redrawn.
2. lobes.png: specular BRDF f(l, v) in the plane of incidence, light at 45 deg, white metal
   (F = 1), for GGX and Beckmann with each visibility term, and the energy-normalised
   Blinn-Phong lobe at the matching shininess (shininess_from_roughness, Walter et al. 2007).
3. albedo.png: directional albedo of a white metal against perceptual roughness, single
   scattering (dashed) and with multiple-scattering compensation (solid), several view angles.
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from addon.reference import brdf, shading  # noqa: E402
from addon.scene.snapshot import MaterialParams, Terms, shininess_from_roughness  # noqa: E402

OUT = ROOT / "docs" / "figures"
DPI = 100
N = np.array([0.0, 0.0, 1.0])
CHANNELS = (("r", "tab:red"), ("g", "tab:green"), ("b", "tab:blue"))

# Complex IOR n + ik at 650 / 550 / 450 nm (r, g, b), linearly interpolated from the luxpop.com
# optical-constant tables that Mitsuba 3 ships as data/ior/{Cu,Al}.{eta,k}.spd (the same values
# as tests/test_reference.py). Glass: IOR 1.5 at all three wavelengths.
COPPER = ((0.2166, 0.9582, 1.1658), (3.6377, 2.5771, 2.3939))
ALUMINIUM = ((1.4748, 0.9586, 0.6180), (7.7941, 6.6870, 5.4694))


def _srgb(linear):
    c = np.clip(linear, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1.0 / 2.4) - 0.055)


def fresnel_figure(path: Path) -> None:
    sin_t = np.linspace(0.0, 1.0, 401)
    cos_t = np.sqrt(1.0 - sin_t ** 2)
    materials = {
        "glass (IOR 1.5)": np.repeat(brdf.F_Dielectric(1.5, cos_t)[:, None], 3, axis=1),
        "copper": brdf.F_Conductor(np.array(COPPER[0]), np.array(COPPER[1]), cos_t),
        "aluminium": brdf.F_Conductor(np.array(ALUMINIUM[0]), np.array(ALUMINIUM[1]), cos_t),
    }
    fig = plt.figure(figsize=(12.0, 4.6))
    grid = fig.add_gridspec(2, 3, height_ratios=(6, 1), hspace=0.35, wspace=0.22)
    ones = np.ones_like(cos_t)
    for col, (name, exact) in enumerate(materials.items()):
        f0 = exact[0]  # sin(theta) = 0: normal incidence
        schlick = brdf.F_Schlick(f0, ones, cos_t)
        sg = brdf.F_SchlickSG(f0, ones, cos_t)
        ps = np.linspace(0.01, 0.5, 491)  # eq. 1.13's p, least squares over sin(theta)
        errs = [np.sum((brdf.F_SchlickGeneral(f0, ones, p, cos_t) - exact) ** 2) for p in ps]
        p = float(ps[int(np.argmin(errs))])
        general = brdf.F_SchlickGeneral(f0, ones, p, cos_t)
        ax = fig.add_subplot(grid[0, col])
        channels = CHANNELS[:1] if col == 0 else CHANNELS
        for c, (_, colour) in enumerate(channels):
            colour = "0.2" if col == 0 else colour
            ax.plot(sin_t, exact[:, c], "-", color=colour, lw=1.6)
            ax.plot(sin_t, schlick[:, c], "--", color=colour, lw=1.1)
            ax.plot(sin_t, sg[:, c], ":", color=colour, lw=1.1)
            ax.plot(sin_t, general[:, c], "-.", color=colour, lw=0.9, alpha=0.7)
        ax.set_title(name)
        ax.set_xlim(0.0, 1.0)
        ax.set_ylim(0.0, 1.02)
        ax.set_xlabel(r"$\sin\theta_i$")
        ax.grid(alpha=0.3)
        if col == 0:
            ax.set_ylabel("Fresnel reflectance F")
        err = np.abs(schlick - exact).max()
        ax.text(0.03, 0.55 if col == 0 else 0.3, f"max |Schlick - exact| = {err:.3f}\n"
                f"generalised: p = {p:.3f}", transform=ax.transAxes, va="top", fontsize=8)
        strip = fig.add_subplot(grid[1, col])
        strip.imshow(_srgb(np.stack([exact, schlick])[:, ::4]), aspect="auto", extent=(0, 1, 0, 2),
                     interpolation="nearest")
        strip.set_yticks([0.5, 1.5], ["Schlick", "exact"], fontsize=8)
        strip.set_xticks([])
    handles = [plt.Line2D([], [], color="0.2", ls=ls, label=lab) for ls, lab in
               (("-", "exact Fresnel"), ("--", "Schlick (1.11)"), (":", "spherical-Gaussian Schlick (1.12)"),
                ("-.", "generalised Schlick (1.13), fitted p"))]
    fig.legend(handles=handles, loc="upper center", ncol=4, fontsize=9, frameon=False)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def _microfacet_brdf(ndf, visibility, roughness, l, v):
    mat = MaterialParams(base_color=(1.0, 1.0, 1.0), metalness=1.0, roughness=roughness)
    s = shading.Surface(np.zeros_like(v), np.broadcast_to(N, v.shape), v, mat)
    out = shading.pbr_direct(s, l, np.ones_like(l), (0.0, 1.0), Terms(ndf=ndf, visibility=visibility))
    return out[:, 0] / l[:, 2]


def _blinn_phong_brdf(shininess, l, v):
    mat = MaterialParams(diffuse_color=(0.0, 0.0, 0.0), specular_color=(1.0, 1.0, 1.0), shininess=shininess)
    s = shading.Surface(np.zeros_like(v), np.broadcast_to(N, v.shape), v, mat)
    out = shading.blinn_phong_direct(s, l, np.ones_like(l), (1.0, 1.0), Terms(normalized_blinn_phong=True))
    return out[:, 0] / l[:, 2]


def lobes_figure(path: Path) -> None:
    incidence = np.radians(45.0)
    theta_v = np.radians(np.linspace(-89.5, 89.5, 719))
    v = np.stack([np.sin(theta_v), np.zeros_like(theta_v), np.cos(theta_v)], -1)
    l = np.broadcast_to([-np.sin(incidence), 0.0, np.cos(incidence)], v.shape)
    styles = {"SMITH_CORRELATED": ("tab:blue", "-", "Smith height-correlated"),
              "SMITH_SEPARABLE": ("tab:orange", "--", "Smith separable"),
              "VCAVITY": ("tab:green", "-.", "V-cavity (Cook-Torrance)"),
              "APPROX": ("tab:purple", ":", "approximate (Hammon / Schlick-Beckmann)")}
    fig, axes = plt.subplots(2, 2, figsize=(9.0, 6.6), subplot_kw={"projection": "polar"})
    for row, roughness in enumerate((0.3, 0.6)):
        s = shininess_from_roughness(roughness)
        bp = _blinn_phong_brdf(s, l, v)
        for col, ndf in enumerate(("GGX", "BECKMANN")):
            ax = axes[row, col]
            peak = 0.0
            for visibility, (colour, ls, label) in styles.items():
                f = _microfacet_brdf(ndf, visibility, roughness, l, v)
                peak = max(peak, f.max())
                ax.plot(theta_v, f, ls, color=colour, lw=1.3, label=label)
            ax.plot(theta_v, bp, "-", color="0.35", lw=1.0, label="Blinn-Phong, (s+8)/(8π) (n·h)^s")
            rmax = 1.08 * max(peak, bp.max())
            ax.plot([-incidence, -incidence], [0.0, rmax], color="goldenrod", lw=1.0)
            ax.annotate("light", xy=(-incidence, 0.9 * rmax), color="goldenrod", fontsize=8)
            ax.set_theta_zero_location("N")
            ax.set_theta_direction(-1)
            ax.set_thetamin(-90)
            ax.set_thetamax(90)
            ax.set_rmax(rmax)
            ax.set_rticks(np.round(np.linspace(0.0, rmax, 4)[1:], 1))
            ax.tick_params(labelsize=7)
            ax.set_title(f"{ndf}, r = {roughness} (α = {roughness ** 2:.2f}); Blinn-Phong s = {s:.1f}",
                         fontsize=9, pad=-4)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=8, frameon=False)
    fig.suptitle("specular BRDF f(l, v) of a white metal in the plane of incidence, light at 45°",
                 fontsize=10, y=0.995)
    fig.subplots_adjust(hspace=0.12, wspace=0.05, top=0.9, bottom=0.06, left=0.03, right=0.97)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def _half_vector_grid(alpha, nu=192, nphi=48):
    """Half vectors on theta = atan(alpha tan(pi u / 2)), phi over a half turn (symmetric lobe)."""
    u = (np.arange(nu) + 0.5) / nu
    t = np.tan(0.5 * np.pi * u)
    theta = np.arctan(alpha * t)
    dtheta = alpha * 0.5 * np.pi / np.cos(0.5 * np.pi * u) ** 2 / (1.0 + (alpha * t) ** 2) / nu
    phi = (np.arange(nphi) + 0.5) / nphi * np.pi
    T, P = np.meshgrid(theta, phi, indexing="ij")
    h = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1).reshape(-1, 3)
    dh = ((np.sin(theta) * dtheta)[:, None] * (2.0 * np.pi / nphi) * np.ones_like(P)).reshape(-1)
    return h, dh


def directional_albedo(ndf, visibility, roughness, view_deg, multiscatter):
    """int f_spec(l, v) (n.l) dl of a white metal, by quadrature over half vectors (dl = 4 v.h dh)."""
    h, dh = _half_vector_grid(max(roughness, brdf.MIN_PERCEPTUAL_ROUGHNESS) ** 2)
    mat = MaterialParams(base_color=(1.0, 1.0, 1.0), metalness=1.0, roughness=roughness)
    terms = Terms(ndf=ndf, visibility=visibility, multiscatter=multiscatter)
    out = []
    for deg in view_deg:
        t = np.radians(deg)
        v = np.array([np.sin(t), 0.0, np.cos(t)])
        VoH = h @ v
        l = 2.0 * VoH[:, None] * h - v
        keep = (VoH > 0.0) & (l[:, 2] > 0.0)
        vv = np.broadcast_to(v, (keep.sum(), 3))
        s = shading.Surface(np.zeros_like(vv), np.broadcast_to(N, vv.shape), vv, mat)
        f = shading.pbr_direct(s, l[keep], np.ones_like(vv), (0.0, 1.0), terms)[:, 0]
        out.append(np.sum(f * dh[keep] * 4.0 * VoH[keep]))
    return np.array(out)


def albedo_figure(path: Path) -> None:
    roughness = np.concatenate([np.linspace(0.0, 0.95, 39), [0.97, 0.98, 0.99, 1.0]])
    views = (0, 45, 75, 85)
    colours = ("tab:blue", "tab:orange", "tab:green", "tab:red")
    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.2), sharey=True)
    for ax, ndf in zip(axes, ("GGX", "BECKMANN")):
        for ms, ls in ((False, "--"), (True, "-")):
            curves = np.array([directional_albedo(ndf, "SMITH_CORRELATED", float(r), views, ms)
                               for r in roughness])
            for i, (deg, colour) in enumerate(zip(views, colours)):
                label = f"θv = {deg}°" if ms else None
                ax.plot(roughness, curves[:, i], ls, color=colour, lw=1.3, label=label)
        ax.axhline(1.0, color="0.5", lw=0.7)
        ax.set_title(f"{ndf} + Smith height-correlated, white metal", fontsize=10)
        ax.set_xlabel("perceptual roughness r (α = r²)")
        ax.set_xlim(0.0, 1.0)
        ax.set_ylim(0.0, 1.05)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("directional albedo ∫ f (n·l) dl")
    axes[0].legend(fontsize=8, loc="lower left", title="solid: multiscatter, dashed: single",
                   title_fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def main() -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    for name, draw in (("fresnel.png", fresnel_figure), ("lobes.png", lobes_figure),
                       ("albedo.png", albedo_figure)):
        path = OUT / name
        draw(path)
        print(f"{path.relative_to(ROOT)} ({path.stat().st_size // 1024} KB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
