//! Layout echo: the GPU reads every shared struct (the push constant structs included) at GLSL's offsets
//! and writes its scalars in declaration order; they must equal the Rust mirror's fields in order.

use bounce_device::{vk, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorWrites};
use bounce_graph::shader_types::*;
use bounce_tests::TestGpu;

#[test]
fn shared_structs_have_the_same_layout_in_glsl_and_rust() {
    let gpu = TestGpu::new();
    // Distinct values everywhere, so a shifted field cannot match by accident.
    let mut k = 0u32;
    let mut next = || {
        k += 1;
        k as f32 + 0.25
    };
    let v = Vertex { position_u: [next(), next(), next(), next()], normal_v: [next(), next(), next(), next()] };
    let m = Material { kd_tex: [next(), next(), next(), next()] };
    let t = TextureInfo { offset: 1001, width: 1002, height: 1003, pad: 1004 };
    let l = Light { position: [next(), next(), next(), next()], intensity: [next(), next(), next(), next()] };
    let mut f = FrameUniforms::default();
    for c in 0..4 {
        for r in 0..4 {
            f.view_proj[c][r] = next();
        }
    }
    f.eye = [next(), next(), next(), next()];
    f.scene_min = [next(), next(), next(), next()];
    f.scene_max = [next(), next(), next(), next()];
    f.size = [2001, 2002, 2003, 2004];
    f.maps = [2501, 2502, 2503, 2504];
    f.shadow = [next(), next(), next(), next()];
    f.voxel_origin = [next(), next(), next(), next()];
    f.voxel_dims = [3001, 3002, 3003, 3004];
    f.light_map = [3501, 3502, 3503, 3504];
    f.vpl = [next(), next(), next(), next()];
    for c in 0..4 {
        for r in 0..4 {
            f.prev_view_proj[c][r] = next();
        }
    }
    f.camera = [next(), next(), next(), next()];
    let gp = GatherPush {
        mode: 4001,
        samples: 4002,
        seed: 4003,
        first: 4004,
        last: 4005,
        accumulate: 4006,
        add_direct: 4007,
        clamp_d2: next(),
        sections: 4009,
        defensive: next(),
        face_mode: 4011,
        cdf_len: 4012,
        rays: 4013,
        end_balls: 4014,
        near_share: next(),
        near_radius: 4016,
    };
    let pv = PsmView { position_v: [next(), next(), next(), next()], normal_p: [next(), next(), next(), next()] };
    let ip = ImportancePush {
        mode: 5001,
        samples: 5002,
        seed: 5003,
        regions: 5004,
        min_d2: next(),
        fixed_scale: next(),
        section: 5007,
        first: 5008,
    };
    let cp = CdfPush { stage: 6001, row_length: 6002, rows: 6003, section: 6004 };
    let vp = VoxelizePush { cells_per_invocation: 7001, first_triangle: 7002 };
    let pp = ParaboloidPush { map_res: 8001, pad: 8002, offset: [next(), next()] };
    let pr = PresentPush {
        stage: 9001,
        frames: next(),
        reset: 9003,
        swap_rb: 9004,
        exposure: next(),
        groups: 9006,
        prior: 9007,
        pad: 9008,
    };
    let rp = ReprojectPush { history: 9501, plane: next(), normal: next(), pad: 9504 };
    let dp = DenoisePush {
        history: 9601,
        step: 9602,
        last: 9603,
        add_direct: 9604,
        alpha: next(),
        sigma_l: next(),
        sigma_n: next(),
        sigma_z: next(),
    };
    let mut input = vec![];
    input.extend_from_slice(bytemuck::bytes_of(&v));
    input.extend_from_slice(bytemuck::bytes_of(&m));
    input.extend_from_slice(bytemuck::bytes_of(&t));
    input.extend_from_slice(bytemuck::bytes_of(&l));
    input.extend_from_slice(bytemuck::bytes_of(&f));
    input.extend_from_slice(bytemuck::bytes_of(&gp));
    input.extend_from_slice(bytemuck::bytes_of(&pv));
    input.extend_from_slice(bytemuck::bytes_of(&ip));
    input.extend_from_slice(bytemuck::bytes_of(&cp));
    input.extend_from_slice(bytemuck::bytes_of(&vp));
    input.extend_from_slice(bytemuck::bytes_of(&pp));
    input.extend_from_slice(bytemuck::bytes_of(&pr));
    input.extend_from_slice(bytemuck::bytes_of(&rp));
    input.extend_from_slice(bytemuck::bytes_of(&dp));

    let inb = Buffer::with_data(&gpu, "echo in", vk::BufferUsageFlags::STORAGE_BUFFER, &input).unwrap();
    let outb = Buffer::new(&gpu, &BufferDesc::storage("echo out", input.len() as u64)).unwrap();
    let p = ComputePipeline::new(
        &gpu,
        "layout_echo",
        &bounce_graph::spirv(bounce_graph::shaders::LAYOUT_ECHO_COMP),
        &[Binding::storage_buffer(0), Binding::storage_buffer(1)],
        0,
        &[],
    )
    .unwrap();
    gpu.submit(|cmd| {
        let w = DescriptorWrites::new().storage_buffer(0, &inb).storage_buffer(1, &outb);
        p.dispatch(cmd, &w, &[], [1, 1, 1], [1, 1, 1]);
    })
    .unwrap();
    let out = outb.read_back(bounce_device::sync::Access::ComputeWrite).unwrap();
    let got: Vec<u32> = bytemuck::pod_collect_to_vec(&out);
    let want: Vec<u32> = bytemuck::pod_collect_to_vec(&input);
    assert_eq!(got, want);
}
