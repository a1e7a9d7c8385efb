// variant: gather.comp EXACT_VISIBILITY
// gather with exact visibility (`--visibility exact`): shadow rays against the triangles (BVH) instead of
// the voxel march. build.rs compiles gather.comp with EXACT_VISIBILITY defined for this file.
