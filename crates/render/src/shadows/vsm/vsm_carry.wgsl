// Virtual shadow maps, carrying last frame's needs over (carry.rs; composed after
// vsm_table.wgsl): cs_carry, the first page pass of a frame marked incrementally (the camera,
// the lights and every face unchanged since the last frame, only casters moved). Every page
// resident or denied last frame is asked again, one thread per entry, and its ancestors are
// marked above; the marking (vsm_mark.wgsl or vsm_tiles.wgsl) then visits only the pixels the
// moved casters may cover. (Last frame's resident pages of the admitted level A may have been
// ancestors only; carried as asked they stay resident while only casters move.)
//
// Which faces may keep last frame's pages (`table.w`) and where casters moved in them
// (`dirty`) is decided on the CPU (carry.rs); which pages keep their depth, by
// vsm_alloc.wgsl's cs_retain.
@compute @workgroup_size(64, 1, 1)
fn cs_carry(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let e = gid.x + gid.y * groups.x * 64u;
    if (e >= vsm.counts.y) {
        return;
    }
    let face = vsm_faces[face_of(e)];
    if (face.table.w == 0u) {
        return;
    }
    let local = e - face.table.x;
    let before = prev_table[face.table.w - 1u + local];
    if (before < VSM_FIRST_PAGE || (before >= VSM_NEEDED_AT && before != VSM_DENIED)) {
        return;
    }
    // The samples are last frame's (cs_mark adds those under the moved casters): so are their
    // receiver bounds, or the bounds the page was drawn with, which cover them. Before the
    // entry's mark: another thread's walk up may have marked it already (as an ancestor).
    if (vsm.counts.w != 0u) {
        let at = face.table.w - 1u + local;
        atomicMax(&vsm_table[vsm.counts.y + e], prev_table[prev_keys_at() + at]);
        atomicOr(&vsm_table[cells_at() + e], prev_table[prev_cells_at() + at]);
    }
    ask_entry(face, e);
}
