// Whitted's 1980 scene for POV-Ray 3.7: the same scene as examples/whitted/classic.yaml, written by hand, for
// benchmarks/bench_whitted.py. Render (PEERS.md):
//
//     povray -D -V +W1024 +H768 +A0.05 +AM2 +R3 +WT2 +Oout.png benchmarks/scenes/whitted.pov
//
// Same objects (a box, two spheres), same two point lights, same camera and framing, same recursion depth and
// the same adaptive anti-aliasing settings (+A0.05 +AM2 +R3 = adaptive_threshold 0.05, adaptive_depth 2: POV-Ray's
// depth counts the pixel itself, so +R3 cuts a pixel twice at most, as its statistics show: 21 extra samples per
// pixel at +A0.0 +R3, i.e. 5 + 16, and 0 at +R1).
// It need not match lumos pixel for pixel: POV-Ray's finishes (transparent pigments, Fresnel reflection,
// conserve_energy) are not lumos's illumination model, only close to it.
//
// Coordinates: lumos is right-handed with y up and POV-Ray left-handed with y up, so every lumos point
// (x, y, z) is written here as <x, y, -z>. The mirror image of a right-handed scene in a left-handed system is
// the same picture: x still points right on the screen and y up, and the camera looks along +z instead of -z.

#version 3.7;

global_settings {
  max_trace_level 5       // counts the camera ray: 4 bounces after it, lumos's max_depth 4
  assumed_gamma 1.0       // colours are linear, as in lumos
  ambient_light rgb 0.12  // lumos's ambient: Ia
}

// lumos: position [0, 2.5, 6.5], look_at [0, 0.8, 0], vertical fov 45 degrees. POV-Ray's `angle` is the
// horizontal field of view over the `right` vector: 2 atan(W/H tan(fov/2)), 57.8 degrees at 4:3.
camera {
  perspective
  location <0, 2.5, -6.5>
  up y
  right x * image_width / image_height
  angle 2 * degrees(atan(image_width / image_height * tan(radians(45 / 2))))
  look_at <0, 0.8, 0>
}

background { color rgb <0.30, 0.55, 0.90> }  // the sky

// Two point lights, no fall-off (POV-Ray's default, lumos's attenuation [1, 0, 0]); both cast shadows.
light_source { <-4, 7, -6> color rgb 0.85 }
light_source { <5, 5, -2> color rgb 0.4 }

// The board: lumos's box min [-4, -0.2, -6], max [4, 0, 5] with a checker of 16 x 22 squares of half a unit.
// POV-Ray's checker is a 3-D pattern of unit cubes: scaled to half a unit, then moved up by a quarter so that the
// top face (y = 0) runs through the middle of a layer of cubes rather than along their faces.
box {
  <-4, -0.2, -5>, <4, 0, 6>
  pigment {
    checker color rgb <0.80, 0.08, 0.05> color rgb <0.90, 0.78, 0.10>
    scale 0.5
    translate y * 0.25
  }
  finish { ambient 1 diffuse 1 phong 0.1 phong_size 10 }  // ka = kd = the checks' colour
}

// The mirror sphere: ka 0.05, kd 0.08, ks 0.6, n 80, kr 0.8.
sphere {
  <-1.1, 1.0, 1.4>, 1.0
  pigment { color rgb 1 }
  finish { ambient 0.05 diffuse 0.08 phong 0.6 phong_size 80 reflection 0.8 }
}

// The glass sphere: kd 0.03, ks 0.7, n 200, kt 0.9, ior 1.5, Fresnel-weighted reflection.
// transmit 0.9 lets 90% of the refracted light through and scales the surface's own diffuse light by 0.1
// (diffuse 0.3 x 0.1 = 0.03); reflection { 0, 1 fresnel on } with conserve_energy takes the reflected share
// from the transmitted one.
sphere {
  <0.45, 1.3, -1.3>, 0.7
  pigment { color rgbt <1, 1, 1, 0.9> }
  finish {
    ambient 0 diffuse 0.3 phong 0.7 phong_size 200
    reflection { 0, 1 fresnel on }
    conserve_energy
  }
  interior { ior 1.5 }
}
