use manyshadows_scene::builtin::*;
#[test]
fn probe() {
    for name in SCENE_NAMES {
        let s = build(name, &BuiltinOptions::default()).unwrap();
        let mut per_mesh = vec![0usize; s.meshes.len()];
        for i in &s.instances { per_mesh[i.mesh] += 1; }
        println!("{name}: tris {} instances {} meshes {} lights {:?} bounds {:?}", s.triangle_count(), s.instances.len(), s.meshes.len(),
            s.lights.iter().map(|l| l.type_name()).collect::<Vec<_>>(), s.world_bounds(false));
        for (m, c) in s.meshes.iter().zip(&per_mesh) { println!("   {} x{} = {} tris each", m.name, c, m.triangle_count()); }
    }
}
