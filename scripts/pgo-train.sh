#!/usr/bin/env bash
# The training run of fgf's profile-guided build (scripts/setup.sh): small
# versions of the jobs users run, with the instrumented native module
# installed in ./.venv. The profile it leaves says which branches and calls
# are hot; the final build lays out and inlines the code by it. Code that
# this run does not reach is compiled as colder, so it covers every medium,
# BSDF family, emitter and query the renderer has, plus field synthesis and
# the transmittance model. Takes about 10 s on 2 cores.
#
#   bash scripts/pgo-train.sh OUT_DIR
set -euo pipefail
cd "$(dirname "$0")/.."
out="$1"
mkdir -p "$out"
. .venv/bin/activate
render() {
    fgf render "$@" --quiet -o "$out/render.exr" --png "$out/render.png"
}
# Homogeneous, heterogeneous (majorant grid) and classical media behind null
# boundaries, under an area light.
render scenes/reference/cube-homogeneous.xml --spp 32 -D res=96
render scenes/reference/cube-heterogeneous.xml --spp 16 -D res=96
# Non-exponential media: both FGF kernels, k-fBm, Davis, Davis-Weinstein.
render scenes/fgf-cube-pink.xml --spp 16 -D res=64
render scenes/fgf-cube-pink.xml --spp 16 -D res=64 -D kernel=reciprocal
render scenes/fgf-cube-2fbm.xml --spp 16 -D res=64
for medium in davis davis_weinstein fgf homogeneous; do
    render scenes/figures/medium_on_ground.xml --spp 8 -D res=64 -D medium=$medium
done
render scenes/figures/striped_wall.xml --spp 8 -D res=64
# Surfaces: a 120,000-triangle mesh, rough BSDFs, a texture and an
# environment map; dielectrics with a medium inside; a spot light.
python benchmarks/make_mesh_envmap.py >/dev/null
render scenes/reference/mesh-envmap.xml --spp 16 -D res=128
render scenes/glass-medium.xml --spp 16 -D res=64
render scenes/spot-sphere.xml --spp 16 -D res=64
render scenes/default.xml --spp 4
# What the repository's scenes leave out: the other BSDFs (principled,
# conductor, plastic, rough and thin dielectrics, a mask, a textured
# two-sided floor), point, directional and constant lights, spheres and
# disks, under `path` and under `direct`.
zoo() { # integrator element
    cat <<XML
<scene version="3.0.0">
    $1
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 2, 6" target="0, 0.5, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="0.3"/></emitter>
    <emitter type="point"><point name="position" x="2" y="4" z="3"/><rgb name="intensity" value="30"/></emitter>
    <emitter type="directional"><vector name="direction" x="-1" y="-1" z="-0.5"/><rgb name="irradiance" value="1"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="twosided"><bsdf type="diffuse">
            <texture type="checkerboard" name="reflectance"><rgb name="color0" value="0.2"/><rgb name="color1" value="0.7"/></texture>
        </bsdf></bsdf>
    </shape>
    <shape type="sphere"><point name="center" x="-1.5" y="0.5" z="0"/><float name="radius" value="0.5"/>
        <bsdf type="principled"><rgb name="base_color" value="0.8, 0.3, 0.2"/><float name="roughness" value="0.4"/><float name="metallic" value="0.3"/></bsdf></shape>
    <shape type="sphere"><point name="center" x="-0.5" y="0.5" z="0"/><float name="radius" value="0.5"/>
        <bsdf type="conductor"/></shape>
    <shape type="sphere"><point name="center" x="0.5" y="0.5" z="0"/><float name="radius" value="0.5"/>
        <bsdf type="plastic"/></shape>
    <shape type="sphere"><point name="center" x="1.5" y="0.5" z="0"/><float name="radius" value="0.5"/>
        <bsdf type="roughdielectric"><float name="alpha" value="0.2"/></bsdf></shape>
    <shape type="disk">
        <transform name="to_world"><scale value="0.6"/><translate x="0" y="1.2" z="1.2"/></transform>
        <bsdf type="thindielectric"/></shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="0.5"/><translate x="-1" y="1.5" z="-1"/></transform>
        <bsdf type="mask">
            <texture type="checkerboard" name="opacity"><float name="color0" value="0"/><float name="color1" value="1"/></texture>
            <bsdf type="diffuse"/>
        </bsdf></shape>
</scene>
XML
}
zoo '<integrator type="path"><integer name="max_depth" value="8"/></integrator>' >"$out/zoo-path.xml"
zoo '<integrator type="direct"/>' >"$out/zoo-direct.xml"
render "$out/zoo-path.xml"
render "$out/zoo-direct.xml"
# Field synthesis and the transmittance model.
fgf field --shape 64 64 64 --hurst -0.5 --sw 2 --seed 1 -o "$out/field.npy" -q
fgf field --shape 128 128 --hurst 0.4 --seed 2 -o "$out/field2.npy" -q
fgf transmittance --sigma-t 4 --hurst -0.1 --sw 4 -o "$out/transmittance.png" >/dev/null 2>&1
