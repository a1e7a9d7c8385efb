// variant: dprsm.geom PSM_VIEW
// psm (maps): the light maps' geometry shader with the viewpoint of VPL k (instance k, layer k) from
// the shared set: one hemisphere around the VPL's normal instead of a light's two faces. The fragment
// shader is dprsm.frag (exact per-texel depth); see crates/graph/src/passes/psm.rs.
