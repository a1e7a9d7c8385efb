// variant: mis.comp EXACT_VISIBILITY
// mis with exact visibility (`--visibility exact`): shadow rays against the triangles (BVH) instead of
// the voxel march. build.rs compiles mis.comp with EXACT_VISIBILITY defined for this file.
