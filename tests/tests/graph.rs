//! The pass graph's own behaviour: culling of passes whose outputs nothing consumes, dependency chains
//! kept alive, and barriers that make one pass's writes visible to the next (validated, and checked by
//! reading the data back).

use bounce_device::sync::Access;
use bounce_device::{vk, Image, ImageDesc};
use bounce_graph::graph::{Graph, Handle, PassContext};
use bounce_tests::TestGpu;

fn image(g: &mut Graph, name: &str) -> Handle<Image> {
    g.create_image(ImageDesc::new(
        name,
        4,
        4,
        vk::Format::R32G32B32A32_SFLOAT,
        vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC,
    ))
}

fn clear(ctx: &PassContext, h: &Handle<Image>, v: f32) {
    let img = ctx.image(h);
    let c = vk::ClearColorValue { float32: [v; 4] };
    unsafe {
        ctx.gpu.device.cmd_clear_color_image(
            ctx.cmd,
            img.raw,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &c,
            &[img.full_range()],
        )
    };
}

fn copy(ctx: &PassContext, src: &Handle<Image>, dst: &Handle<Image>) {
    let (s, d) = (ctx.image(src), ctx.image(dst));
    let layers = vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1);
    let region = vk::ImageCopy::default().src_subresource(layers).dst_subresource(layers).extent(vk::Extent3D {
        width: 4,
        height: 4,
        depth: 1,
    });
    unsafe {
        ctx.gpu.device.cmd_copy_image(
            ctx.cmd,
            s.raw,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            d.raw,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &[region],
        )
    };
}

#[test]
fn unused_passes_are_culled_and_chains_kept() {
    let gpu = TestGpu::new();
    let mut g = Graph::new(&gpu);
    let mut a = image(&mut g, "a");
    let mut b = image(&mut g, "b");
    let mut unused = image(&mut g, "unused");
    let ha = a;
    g.add_pass("make_a").overwrite(&mut a, Access::TransferWrite).record(move |ctx| clear(ctx, &ha, 3.0));
    let hu = unused;
    g.add_pass("make_unused").overwrite(&mut unused, Access::TransferWrite).record(move |ctx| clear(ctx, &hu, 9.0));
    let hb = b;
    g.add_pass("copy_a_to_b")
        .read(&a, Access::TransferRead)
        .overwrite(&mut b, Access::TransferWrite)
        .record(move |ctx| copy(ctx, &ha, &hb));
    g.export(&b);
    let done = g.execute().unwrap();
    assert_eq!(done.ran, vec!["make_a", "copy_a_to_b"]);
    assert_eq!(done.skipped, vec!["make_unused"]);
    let px: Vec<f32> = bytemuck::pod_collect_to_vec(&done.read_image(&b).unwrap());
    assert!(px.iter().all(|&v| v == 3.0), "the copy did not see the clear: {px:?}");
    assert_eq!(done.timings.len(), 2);
}

#[test]
fn an_overwrite_kills_earlier_writers_but_a_write_keeps_them() {
    let gpu = TestGpu::new();
    let mut g = Graph::new(&gpu);
    let mut x = image(&mut g, "x");
    let hx = x;
    g.add_pass("first").overwrite(&mut x, Access::TransferWrite).record(move |ctx| clear(ctx, &hx, 1.0));
    g.add_pass("second").overwrite(&mut x, Access::TransferWrite).record(move |ctx| clear(ctx, &hx, 2.0));
    g.export(&x);
    let done = g.execute().unwrap();
    assert_eq!(done.ran, vec!["second"]);
    assert_eq!(done.skipped, vec!["first"]);

    let mut g = Graph::new(&gpu);
    let mut y = image(&mut g, "y");
    let hy = y;
    g.add_pass("first").overwrite(&mut y, Access::TransferWrite).record(move |ctx| clear(ctx, &hy, 1.0));
    g.add_pass("second").write(&mut y, Access::TransferWrite).record(|_| {});
    g.export(&y);
    let done = g.execute().unwrap();
    assert_eq!(done.ran, vec!["first", "second"]);
    let px: Vec<f32> = bytemuck::pod_collect_to_vec(&done.read_image(&y).unwrap());
    assert!(px.iter().all(|&v| v == 1.0));
}

/// The frame-skipping tests' settings: a 24² combined frame of `method`, small maps, the voxel march (so
/// that the grid is made and kept: exact rays need none).
fn small_frame(method: bounce_graph::frame::Method) -> bounce_graph::frame::FrameSettings {
    bounce_graph::frame::FrameSettings {
        width: 24,
        height: 24,
        component: bounce_graph::frame::Component::Combined,
        method,
        vpls: 4,
        dprsm_res: 32,
        voxels: 32,
        visibility: bounce_graph::frame::Visibility::Voxel,
        ..bounce_graph::frame::FrameSettings::default()
    }
}

/// Skipping what a frame does not need: a second frame whose inputs are unchanged records only the
/// gather (read from the graph's list of recorded passes, not from timings) and gives the same image;
/// another seed for `uniform` (whose CDF does not depend on it) still records only the gather; a method
/// whose importance depends on the seed, or another image size, rebuilds.
#[test]
fn an_unchanged_frame_records_only_the_gather() {
    use bounce_graph::frame::{FrameSettings, Method, Renderer};
    use bounce_graph::scene::Scene;
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let s = small_frame(Method::Uniform);
    let first = r.render(&s).unwrap();
    for pass in ["gbuffer", "direct", "dprsm", "voxelize", "importance", "cdf_reduce", "gather"] {
        assert!(first.ran.contains(&pass), "the first frame lacks {pass}: {:?}", first.ran);
    }
    let second = r.render(&s).unwrap();
    assert_eq!(second.ran, vec!["gather"], "an unchanged frame recorded more than the gather");
    assert_eq!(first.radiance, second.radiance);
    // A new seed with the light side's kept (as progressive frames keep it) draws only new picks...
    let reseeded = r.render(&FrameSettings { seed: 99, cdf_seed: Some(s.seed), ..s.clone() }).unwrap();
    assert_eq!(reseeded.ran, vec!["gather"]);
    assert_ne!(reseeded.radiance, first.radiance);
    // Exact shadow rays need no voxel grid: a frame with them never voxelizes.
    let mut exact = Renderer::new(&gpu, &scene).unwrap();
    let e = exact.render(&FrameSettings { visibility: bounce_graph::frame::Visibility::Exact, ..s.clone() }).unwrap();
    assert!(!e.ran.contains(&"voxelize") && !e.skipped.contains(&"voxelize"), "{:?}", e.ran);
    let gbg = FrameSettings { method: Method::Gbg, ..s.clone() };
    assert!(r.render(&gbg).unwrap().ran.contains(&"importance"));
    assert_eq!(r.render(&gbg).unwrap().ran, vec!["gather"]);
    let gbg2 = r.render(&FrameSettings { seed: 5, vpl_seed: Some(s.seed), ..gbg.clone() }).unwrap();
    assert!(gbg2.ran.contains(&"importance"), "gbg's importance depends on the seed: {:?}", gbg2.ran);
    let bigger = r.render(&FrameSettings { width: 32, ..s.clone() }).unwrap();
    assert!(bigger.ran.contains(&"gbuffer"));
    // A resize keeps the light side: the paraboloid maps depend on the lights and their resolution,
    // and so does `uniform`'s importance and CDF (the VPLs' validity): no importance pass, no scan.
    for pass in ["dprsm", "importance", "cdf_reduce"] {
        assert!(!bigger.ran.contains(&pass), "a resize redid {pass}: {:?}", bigger.ran);
    }
    let fresh = Renderer::new(&gpu, &scene).unwrap().render(&FrameSettings { width: 32, ..s.clone() }).unwrap();
    assert_eq!(fresh.radiance, bigger.radiance, "the kept validity CDF changed the image");
    // ...while a new seed alone also puts the VPLs elsewhere in their texels: the maps are redrawn.
    let moved = r.render(&FrameSettings { seed: 99, width: 32, ..s.clone() }).unwrap();
    assert!(moved.ran.contains(&"dprsm"), "a new VPL seed kept the maps: {:?}", moved.ran);
}

/// `Renderer::warm_up` (every `render` runs it before its timed frames, so that a driver's first-use
/// compilation stays out of their GPU time) renders an untimed frame of about 8 × 8 with maps of about 32²
/// and drops what it kept: the next frame, at other sizes, must record every pass a fresh renderer's first
/// frame records and give its image bit for bit. Methods whose frames keep products (gbg's importance, the
/// voxel grid, mis's patches) and ris, whose reservoirs live across frames.
#[test]
fn a_warm_up_leaves_the_next_frame_as_a_first_frame() {
    use bounce_graph::frame::{Component, FrameSettings, Method, Renderer, Visibility};
    use bounce_graph::scene::Scene;
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    for (method, visibility) in [
        (Method::Gbg, Visibility::Voxel),
        (Method::Uniform, Visibility::Exact),
        (Method::Mis, Visibility::Exact),
        (Method::Ris, Visibility::Exact),
    ] {
        let s = FrameSettings {
            width: 24,
            height: 16,
            component: Component::Indirect,
            method,
            vpls: 8,
            dprsm_res: 64,
            voxels: 32,
            visibility,
            ..FrameSettings::default()
        };
        let fresh = Renderer::new(&gpu, &scene).unwrap().render(&s).unwrap();
        let mut warmed = Renderer::new(&gpu, &scene).unwrap();
        warmed.warm_up(&s).unwrap();
        let after = warmed.render(&s).unwrap();
        assert!(fresh.radiance.iter().any(|p| p[0] > 0.0), "{method:?}: black image");
        // A product the warm-up kept would show as a pass this frame skipped.
        assert_eq!(after.ran, fresh.ran, "{method:?}: the frame after a warm-up recorded other passes");
        assert!(after.radiance == fresh.radiance, "{method:?}: the warm-up changed the next frame's image");
    }
}

/// A camera move (the viewer's fly camera) re-records what the camera feeds (G-buffer, direct light,
/// importance, CDF) and keeps the light side (the reflective DPRSM) and the voxels; the image equals a fresh
/// renderer's at the new camera, so nothing stale is reused.
#[test]
fn a_camera_move_keeps_the_light_side() {
    use bounce_graph::frame::{Component, FrameSettings, Method, Renderer};
    use bounce_graph::scene::Scene;
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let s = small_frame(Method::Global);
    r.render(&s).unwrap();
    let mut moved = scene.camera;
    moved.eye += glam::Vec3::new(0.2, -0.1, -0.5);
    r.set_camera(moved);
    let after = r.render(&s).unwrap();
    for pass in ["gbuffer", "direct", "importance", "cdf_reduce", "gather"] {
        assert!(after.ran.contains(&pass), "a camera move must redo {pass}: {:?}", after.ran);
    }
    for pass in ["dprsm", "voxelize"] {
        assert!(!after.ran.contains(&pass), "a camera move must keep {pass}: {:?}", after.ran);
    }
    let mut fresh = Renderer::new(&gpu, &scene).unwrap();
    fresh.set_camera(moved);
    assert_eq!(fresh.render(&s).unwrap().radiance, after.radiance, "the kept light side changed the image");
    assert_eq!(r.render(&s).unwrap().ran, vec!["gather"]);
    // The indirect component keeps the maps without the direct light; a move then must still work (the
    // direct pass is not needed and not recorded).
    let indirect = FrameSettings { component: Component::Indirect, ..s.clone() };
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    r.render(&indirect).unwrap();
    r.set_camera(scene.camera);
    let mut back = scene.camera;
    back.eye.z += 0.1;
    r.set_camera(back);
    let after = r.render(&indirect).unwrap();
    assert!(!after.ran.contains(&"dprsm") && !after.ran.contains(&"direct"), "{:?}", after.ran);
    // And a combined frame after it renders the direct light it lacks, on the kept maps.
    let combined = r.render(&s).unwrap();
    assert!(combined.ran.contains(&"direct") && !combined.ran.contains(&"dprsm"), "{:?}", combined.ran);
}

/// A light move re-records exactly the light-side passes (reflective maps, direct light) and what
/// depends on them (importance, CDF, gather), keeps the voxels and the G-buffer, and gives the image a
/// fresh renderer whose scene has the light there renders; an intensity change redoes both; moving nothing records only the gather; moving the light back gives the first image's
/// bits (the light upload is exact).
#[test]
fn a_light_move_records_exactly_the_light_side() {
    use bounce_graph::frame::{Method, Renderer};
    use bounce_graph::scene::{point_light, Scene};
    use glam::Vec3;
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let s = small_frame(Method::Global);
    let first = r.render(&s).unwrap();
    let (p0, i0) =
        (Vec3::from_slice(&scene.lights[0].position[..3]), Vec3::from_slice(&scene.lights[0].intensity[..3]));
    let p1 = p0 + Vec3::new(0.15, -0.05, 0.1) * scene.diagonal();
    r.set_light(0, p1, i0);
    let moved = r.render(&s).unwrap();
    let light_side = ["direct", "dprsm", "importance", "cdf_reduce", "gather"];
    let mut want: Vec<&str> = first.ran.iter().copied().filter(|p| light_side.contains(p)).collect();
    want.dedup();
    assert_eq!(moved.ran, want, "a light move must record exactly the light side");
    for pass in ["voxelize", "gbuffer"] {
        assert!(first.ran.contains(&pass) && !moved.ran.contains(&pass), "{pass}: {:?}", moved.ran);
    }
    let mut there = scene.clone();
    there.lights[0] = point_light(p1, i0);
    let fresh = Renderer::new(&gpu, &there).unwrap().render(&s).unwrap();
    assert_eq!(fresh.radiance, moved.radiance, "a kept product is stale after the light move");
    assert_ne!(fresh.radiance, first.radiance, "the light move changed nothing");
    assert_eq!(r.render(&s).unwrap().ran, vec!["gather"], "moving nothing records only the gather");
    r.set_light(0, p1, i0 * 2.0);
    let brighter = r.render(&s).unwrap();
    assert!(brighter.ran.contains(&"direct") && brighter.ran.contains(&"dprsm"), "{:?}", brighter.ran);
    r.set_light(0, p0, i0);
    assert_eq!(r.render(&s).unwrap().radiance, first.radiance, "moving the light back changed the bits");
}

/// A paraboloid face that sees nothing (zero flux: all the geometry lies on one side of the light) is
/// never sampled. With one live face, Russian roulette (probability ∝ face total) and the uniform face
/// choice (uniform among faces with importance) both give it probability 0 and draw every sample from
/// the other face, so their images are identical; and, like every face, it is rendered once and then
/// reused by the light cache.
#[test]
fn an_empty_paraboloid_face_is_never_sampled() {
    use bounce_graph::camera::Camera;
    use bounce_graph::frame::{Component, FaceMode, FrameSettings, Method, Renderer};
    use bounce_graph::scene::{point_light, Scene};
    use glam::Vec3;
    let v = Vec3::new;
    // Everything at z < 0, the light at z = 0.2: its +z face sees nothing.
    let tris = [
        [v(-2.0, 0.0, -2.0), v(2.0, 0.0, -2.0), v(2.0, 0.0, -0.1)],
        [v(-2.0, 0.0, -2.0), v(2.0, 0.0, -0.1), v(-2.0, 0.0, -0.1)],
        [v(-2.0, 0.0, -2.0), v(2.0, 0.0, -2.0), v(2.0, 2.0, -2.0)],
        [v(-2.0, 0.0, -2.0), v(2.0, 2.0, -2.0), v(-2.0, 2.0, -2.0)],
    ];
    let camera = Camera { eye: v(0.0, 1.0, 3.0), target: v(0.0, 0.5, -1.0), up: Vec3::Y, fov_y_deg: 60.0 };
    let scene = Scene::from_triangles(
        &tris,
        &[Vec3::splat(0.6); 4],
        camera,
        &[point_light(v(0.0, 1.0, 0.2), Vec3::splat(3.0))],
    );
    let gpu = TestGpu::new();
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    for method in [Method::Global, Method::Gbg] {
        let s = FrameSettings {
            width: 24,
            height: 24,
            component: Component::Indirect,
            method,
            vpls: 8,
            dprsm_res: 32,
            voxels: 32,
            seed: 3,
            ..FrameSettings::default()
        };
        let rr = r.render(&FrameSettings { face: FaceMode::RussianRoulette, ..s.clone() }).unwrap();
        let uniform = r.render(&FrameSettings { face: FaceMode::Uniform, ..s.clone() }).unwrap();
        assert!(!uniform.ran.contains(&"dprsm"), "the maps are reused: {:?}", uniform.ran);
        let mean = rr.radiance.iter().map(|p| p[0] as f64).sum::<f64>() / rr.radiance.len() as f64;
        assert!(mean > 0.0, "{method:?}: the live face lights the scene");
        assert_eq!(rr.radiance, uniform.radiance, "{method:?}: a face choice drew the empty face");
    }
}

/// A graph of one 4×4 image per test below, cleared by a pass named `make`.
fn make(g: &mut Graph, v: f32) -> Handle<Image> {
    let mut x = image(g, "x");
    let hx = x;
    g.add_pass("make").overwrite(&mut x, Access::TransferWrite).record(move |ctx| clear(ctx, &hx, v));
    x
}

fn read(done: &bounce_graph::graph::Executed, h: &Handle<Image>) -> Vec<f32> {
    bytemuck::pod_collect_to_vec(&done.read_image(h).unwrap())
}

/// A cached product is made once and lent back to later graphs while its key stays the same (its passes
/// are not even added again); another key makes it anew and lends the old one for that graph only
/// (`replaced`: last frame's VPLs after a light moved), then drops it; a product whose passes were culled
/// is not kept.
#[test]
fn cached_products_are_kept_across_graphs_until_their_key_changes() {
    use bounce_graph::graph::Retained;
    let gpu = TestGpu::new();
    let mut kept = Retained::default();
    let mut built = 0;
    for (key, value, want) in [(1, 3.0, 3.0), (1, 5.0, 3.0), (2, 7.0, 7.0), (2, 9.0, 7.0)] {
        let mut g = Graph::with_retained(&gpu, &mut kept);
        let x = g.cached("x", &key, |g| {
            built += 1;
            make(g, value)
        });
        g.export(&x);
        // The key changed from 1 to 2 in the third graph only: the old product is 3.0's.
        let old: Option<Handle<Image>> = g.replaced("x");
        assert_eq!(old.is_some(), (key, value) == (2, 7.0), "key {key}, value {value}");
        if let Some(old) = &old {
            g.export(old);
        }
        let done = g.execute().unwrap();
        assert!(read(&done, &x).iter().all(|&v| v == want), "key {key}: expected {want}");
        if let Some(old) = &old {
            assert!(read(&done, old).iter().all(|&v| v == 3.0), "the replaced product keeps its contents");
        }
        assert_eq!(done.ran.is_empty(), value != want, "key {key}: ran {:?}", done.ran);
    }
    assert_eq!(built, 2);
    assert_eq!(kept.product_names(), ["x"]);

    // Culled: nothing consumes the product, so its pass does not run and nothing is kept.
    let mut g = Graph::with_retained(&gpu, &mut kept);
    g.cached("unused", &0, |g| make(g, 1.0));
    let done = g.execute().unwrap();
    assert_eq!(done.skipped, ["make"]);
    drop(done);
    assert_eq!(kept.product_names(), ["x"]);
}

/// A cached product that names one resource twice is refused where it is declared (it would be taken twice
/// when the frame hands its resources back, inside a drop).
#[test]
#[should_panic(expected = "names a resource twice")]
fn a_cached_product_naming_a_resource_twice_is_refused() {
    use bounce_graph::graph::Retained;
    let gpu = TestGpu::new();
    let mut kept = Retained::default();
    let mut g = Graph::with_retained(&gpu, &mut kept);
    g.cached("twice", &0, |g| {
        let x = make(g, 1.0);
        (x, x)
    });
}

/// A temporal image (or buffer) keeps its contents across graphs and says when they are undefined (first
/// use, a new key); a history image gives the version of the last frame that used it (frames between
/// that did not are skipped), and none once the histories are forgotten.
#[test]
fn temporal_and_history_images_live_across_graphs() {
    use bounce_graph::graph::Retained;
    let gpu = TestGpu::new();
    let mut kept = Retained::default();
    let desc = ImageDesc::new(
        "acc",
        4,
        4,
        vk::Format::R32G32B32A32_SFLOAT,
        vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC,
    );
    for (key, fresh, value) in [(0, true, 1.0), (0, false, 2.0), (1, true, 3.0)] {
        let mut g = Graph::with_retained(&gpu, &mut kept);
        let t = g.temporal_image("acc", desc.clone(), &key);
        assert_eq!(t.fresh, fresh, "key {key}, value {value}");
        let mut h = t.handle;
        let hh = h;
        g.add_pass("write").write(&mut h, Access::TransferWrite).record(move |ctx| clear(ctx, &hh, value));
        g.export(&h);
        assert!(read(&g.execute().unwrap(), &h).iter().all(|&v| v == value));
    }
    // A temporal buffer keeps what the first graph wrote; a second graph only reads it.
    for (fresh, fill) in [(true, Some(7u32)), (false, None)] {
        let mut g = Graph::with_retained(&gpu, &mut kept);
        let t = g.temporal_buffer("counts", bounce_device::BufferDesc::storage("counts", 64), &());
        assert_eq!(t.fresh, fresh);
        let mut h = t.handle;
        if let Some(v) = fill {
            let hh = h;
            g.add_pass("fill").overwrite(&mut h, Access::TransferWrite).record(move |ctx| unsafe {
                ctx.gpu.device.cmd_fill_buffer(ctx.cmd, ctx.buffer(&hh).raw, 0, vk::WHOLE_SIZE, v);
            });
        }
        g.export(&h);
        let done = g.execute().unwrap();
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&done.read_buffer(&h).unwrap());
        assert!(words.iter().all(|&w| w == 7), "{words:?}");
    }
    // Frame 3 does not ask for the history (a frame of another method in the viewer): frame 4 finds the
    // last use's version, frame 2's (swapping at every frame gave it frame 1's, two uses old). Frame 6
    // comes after the histories were forgotten: it has none.
    let mut last_use = None;
    for frame in 0..8u32 {
        if frame == 3 {
            kept.next_frame();
            continue;
        }
        if frame == 6 {
            kept.forget_histories();
            last_use = None;
        }
        let mut g = Graph::with_retained(&gpu, &mut kept);
        let hist = g.history_image("hist", desc.clone(), &());
        assert_eq!(hist.previous.is_some(), last_use.is_some(), "frame {frame}");
        let mut cur = hist.current;
        let hc = cur;
        g.add_pass("write").overwrite(&mut cur, Access::TransferWrite).record(move |ctx| clear(ctx, &hc, frame as f32));
        g.export(&cur);
        let mut prev_copy = image(&mut g, "previous copy");
        if let Some(p) = hist.previous {
            let hp = prev_copy;
            g.add_pass("copy")
                .read(&p, Access::TransferRead)
                .overwrite(&mut prev_copy, Access::TransferWrite)
                .record(move |ctx| copy(ctx, &p, &hp));
            g.export(&prev_copy);
        }
        let done = g.execute().unwrap();
        if let Some(before) = last_use.filter(|_| hist.previous.is_some()) {
            assert!(read(&done, &prev_copy).iter().all(|&v| v == before as f32), "frame {frame}");
        }
        drop(done);
        last_use = Some(frame);
        kept.next_frame();
    }
}

/// A pass may touch only what it declared: the planner derived no barrier for anything else.
#[test]
#[should_panic(expected = "without declaring it")]
fn a_pass_that_uses_an_undeclared_handle_is_refused() {
    let gpu = TestGpu::new();
    let mut g = Graph::new(&gpu);
    let x = make(&mut g, 1.0);
    let mut y = image(&mut g, "y");
    let hy = y;
    g.add_pass("sneaky").overwrite(&mut y, Access::TransferWrite).record(move |ctx| {
        clear(ctx, &hy, 2.0);
        clear(ctx, &x, 2.0);
    });
    g.export(&y);
    let _ = g.execute();
}

/// Progressive rendering under a time budget is exactly the mean of the frames `render` makes with seeds
/// `seed + k`, one CDF seed (`cdf_seed = seed`) and the VPL set it reports for each frame (set 0: the
/// VPL seed a single frame draws; later sets each their own), for as many frames as it reports. With a
/// pinned VPL seed every frame takes it.
#[test]
fn a_time_limited_render_is_the_mean_of_its_frames() {
    use bounce_graph::frame::progressive::{frame_settings, render_for};
    use bounce_graph::frame::{Component, FrameSettings, Method, Renderer};
    use bounce_graph::scene::Scene;
    let gpu = TestGpu::new();
    let scene = Scene::load(&bounce_tests::default_scene()).unwrap();
    let s = FrameSettings {
        width: 16,
        height: 16,
        component: Component::Indirect,
        method: Method::Gbg,
        vpls: 2,
        seed: 7,
        dprsm_res: 16,
        voxels: 16,
        ..FrameSettings::default()
    };
    let mut r = Renderer::new(&gpu, &scene).unwrap();
    let pinned = FrameSettings { vpl_seed: Some(3), ..s.clone() };
    // Hundreds of frames at 16² (measured: 615 in 1.5 s; 175 in 0.5 s, 2 sets): several sets unless pinned.
    let p = render_for(&mut r, &pinned, std::time::Duration::from_millis(400), &mut |_, _| {}).unwrap();
    assert!(p.sets.iter().all(|&j| j == 0) && p.sets.len() == p.frames as usize, "{:?}", p.sets);
    let p = render_for(&mut r, &s, std::time::Duration::from_millis(1500), &mut |_, _| {}).unwrap();
    eprintln!("{} frames, {} VPL sets", p.frames, p.sets.last().map_or(0, |j| j + 1));
    assert_eq!(p.sets.len(), p.frames as usize);
    assert!(p.sets.last().is_some_and(|&j| j >= 1), "one VPL set in {} frames", p.frames);
    let mut fresh = Renderer::new(&gpu, &scene).unwrap();
    let mut sum = vec![[0.0f64; 4]; p.radiance.len()];
    for (k, &set) in p.sets.iter().enumerate() {
        let vpl_seed = frame_settings(&s, k as u32, set).vpl_seed;
        assert_eq!(vpl_seed.is_none(), set == 0, "set {set}: VPL seed {vpl_seed:?}");
        let f = fresh.render(&FrameSettings { seed: 7 + k as u64, cdf_seed: Some(7), vpl_seed, ..s.clone() }).unwrap();
        for (a, x) in sum.iter_mut().zip(&f.radiance) {
            for c in 0..4 {
                a[c] += x[c] as f64;
            }
        }
    }
    let n = p.frames as f64;
    let want: Vec<[f32; 4]> =
        sum.iter().map(|a| [(a[0] / n) as f32, (a[1] / n) as f32, (a[2] / n) as f32, (a[3] / n) as f32]).collect();
    assert_eq!(p.radiance, want, "{} frames", p.frames);
}
