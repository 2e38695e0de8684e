// Shadow lookups through the virtual shadow maps' page table (vsm.rs), for the lighting and
// visibility passes. The includer declares `vsm: VsmUniforms`, `vsm_faces` and `vsm_table`
// (vsm.rs composes the declarations with the pass's binding numbers).

// Where `p` falls in the page pool for `light`: the page of the level the point needs, or, if
// that page is not resident (the pool was full), the nearest coarser resident page. Taps of
// the filter stay inside the page (`tile_min`, `tile_max`), so pages never bleed into each
// other. Invalid (unshadowed) when no level of the face is resident.
fn shadow_coord(light: LightData, p: vec3<f32>, n: vec3<f32>, view_depth: f32) -> ShadowCoord {
    var out: ShadowCoord;
    out.valid = false;
    let fi = select_shadow_view(light, p, view_depth);
    if (fi < 0) {
        return out;
    }
    let face = vsm_faces[fi];
    let ray = vsm_ray(light, face, p, n);
    var level = vsm_level(face, ray, view_depth);
    loop {
        let q = vsm_project(light, face, ray, level);
        if (!q.valid) {
            return out;
        }
        let e = vsm_table[vsm_entry(face, level, q.uv)];
        if (e >= VSM_FIRST_PAGE && e != VSM_DENIED) {
            var page = e - VSM_FIRST_PAGE;
            var side = f32(vsm.pool.z);
            var corner = vec2<f32>(0.0);
            var at = q;
            if (page >= VSM_QUARTER) {
                // A level-0 quarter page: half the side, its texels twice as wide (and the
                // bias with them).
                let k = page - VSM_QUARTER;
                page = k / 4u;
                side = 0.5 * side;
                corner = vec2<f32>(f32(k % 2u), f32((k / 2u) % 2u)) * side;
                at = vsm_project_texel(light, face, ray, 2.0 * vsm_texel_world(face, level, ray));
                if (!at.valid) {
                    return out;
                }
            }
            let tile = vec2<f32>(f32(page % vsm.pool.y), f32(page / vsm.pool.y)) * f32(vsm.pool.z) + corner;
            let pages = f32(1u << level);
            let cell = min(floor(at.uv * pages), vec2<f32>(pages - 1.0));
            out.tile_min = tile;
            out.tile_max = tile + vec2<f32>(side);
            out.texel = tile + (at.uv * pages - cell) * side;
            out.depth = at.depth;
            // The texel of this page per unit of distance (perspective) or in the world.
            let texel = face.params.z * f32(1u << (face.table.y - level)) * select(1.0, 2.0, side < f32(vsm.pool.z));
            out.lin = vec4<f32>(face.params.x, face.params.y, texel, face.params.w);
            out.valid = true;
            return out;
        }
        if (level == 0u) {
            return out;
        }
        level = level - 1u;
    }
    return out;
}
