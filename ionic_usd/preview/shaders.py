"""GLSL 3.30 programs of the preview: lit meshes (shadow-mapped key light, fill, hemispheric
ambient), depth-only passes, card quads (textured, alpha-tested, unlit: the image is already
lit), the sky gradient and the fading ground plane."""

from __future__ import annotations

__all__ = [
    "LIGHTING",
    "MESH_VS",
    "MESH_FS",
    "DEPTH_VS",
    "DEPTH_FS",
    "CARD_VS",
    "CARD_FS",
    "CARD_DEPTH_VS",
    "CARD_DEPTH_FS",
    "BACKGROUND_VS",
    "BACKGROUND_FS",
    "GROUND_VS",
    "GROUND_FS",
]

LIGHTING = """
uniform vec3 u_key, u_fill, u_eye;
uniform mat4 u_light;
uniform sampler2DShadow u_shadow;
uniform float u_texel, u_texel_uv;

float shadow(vec3 p, vec3 n) {
    vec4 q = u_light * vec4(p + n * u_texel * 1.5, 1.0);
    vec3 s = q.xyz * 0.5 + 0.5;
    if (s.x <= 0.0 || s.x >= 1.0 || s.y <= 0.0 || s.y >= 1.0 || s.z >= 1.0) return 1.0;
    float sum = 0.0;
    for (int i = -1; i <= 1; ++i)
        for (int j = -1; j <= 1; ++j)
            sum += texture(u_shadow, vec3(s.xy + vec2(i, j) * u_texel_uv, s.z - 0.0005));
    return sum / 9.0;
}

vec3 shade(vec3 albedo, vec3 p, vec3 n, float gloss) {
    vec3 v = normalize(u_eye - p);
    float lit = shadow(p, n);
    float k = max(dot(n, u_key), 0.0) * lit;
    float f = max(dot(n, u_fill), 0.0);
    vec3 ambient = mix(vec3(0.36, 0.32, 0.27), vec3(0.62, 0.70, 0.80), 0.5 + 0.5 * n.y);
    vec3 h = normalize(u_key + v);
    float spec = gloss * pow(max(dot(n, h), 0.0), 48.0) * k;
    return albedo * (0.36 * ambient + 1.10 * k * vec3(1.0, 0.95, 0.86)
                     + 0.22 * f * vec3(0.70, 0.80, 1.0)) + spec * vec3(1.0, 0.97, 0.9);
}

vec3 to_srgb(vec3 c) {
    c = c / (1.0 + 0.15 * c);  // soft shoulder keeps highlights from clipping flat
    c = clamp(c, 0.0, 1.0);
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(0.0031308, c));
}
"""

MESH_VS = """
#version 330
uniform mat4 u_viewproj;
in vec3 in_pos, in_nrm;
in mat4 in_model;
in mat3 in_nmat;
out vec3 v_pos, v_nrm;
void main() {
    vec4 w = in_model * vec4(in_pos, 1.0);
    v_pos = w.xyz;
    v_nrm = in_nmat * in_nrm;
    gl_Position = u_viewproj * w;
}
"""

MESH_FS = (
    "#version 330\n"
    + LIGHTING
    + """
uniform vec3 u_colour;
in vec3 v_pos, v_nrm;
out vec4 f_colour;
void main() {
    vec3 n = dot(v_nrm, v_nrm) > 1e-20 ? normalize(v_nrm) : vec3(0.0, 1.0, 0.0);
    if (!gl_FrontFacing) n = -n;
    f_colour = vec4(to_srgb(shade(u_colour, v_pos, n, 0.10)), 1.0);
}
"""
)

DEPTH_VS = """
#version 330
uniform mat4 u_viewproj;
in vec3 in_pos;
in mat4 in_model;
void main() { gl_Position = u_viewproj * (in_model * vec4(in_pos, 1.0)); }
"""

DEPTH_FS = "#version 330\nvoid main() {}\n"

BACKGROUND_VS = """
#version 330
in vec2 in_xy;
out float v_t;
void main() { v_t = in_xy.y * 0.5 + 0.5; gl_Position = vec4(in_xy, 0.999999, 1.0); }
"""

BACKGROUND_FS = """
#version 330
uniform vec3 u_top, u_bottom;
in float v_t;
out vec4 f_colour;
void main() { f_colour = vec4(mix(u_bottom, u_top, smoothstep(0.0, 1.0, v_t)), 1.0); }
"""

GROUND_VS = """
#version 330
uniform mat4 u_viewproj;
in vec3 in_pos;
out vec3 v_pos;
void main() { v_pos = in_pos; gl_Position = u_viewproj * vec4(in_pos, 1.0); }
"""

GROUND_FS = (
    "#version 330\n"
    + LIGHTING
    + """
uniform vec3 u_colour;
uniform vec2 u_centre, u_fade;
in vec3 v_pos;
out vec4 f_colour;
void main() {
    float d = length(v_pos.xz - u_centre);
    float a = 1.0 - smoothstep(u_fade.x, u_fade.y, d);
    f_colour = vec4(to_srgb(shade(u_colour, v_pos, vec3(0.0, 1.0, 0.0), 0.0)), a);
}
"""
)

CARD_VS = """
#version 330
uniform mat4 u_viewproj;
in vec3 in_pos;
in vec2 in_uv;
in mat4 in_model;
out vec2 v_uv;
void main() {
    v_uv = in_uv;
    gl_Position = u_viewproj * (in_model * vec4(in_pos, 1.0));
}
"""

CARD_FS = """
#version 330
uniform sampler2D u_image;
in vec2 v_uv;
out vec4 f_colour;
void main() {
    vec4 c = texture(u_image, v_uv);
    if (c.a < 0.5) discard;  // alpha-tested like a viewer's cards: no sorting needed
    f_colour = vec4(c.rgb, 1.0);
}
"""

CARD_DEPTH_VS = CARD_VS

CARD_DEPTH_FS = """
#version 330
uniform sampler2D u_image;
in vec2 v_uv;
void main() { if (texture(u_image, v_uv).a < 0.5) discard; }
"""
