// variant: gather.comp PSM_VISIBILITY PSM_EXACT EXACT_VISIBILITY
// gather with `--visibility psm-exact`: the frame's shared VPL set (as `psm`) with exact shadow rays
// against the BVH: the reference for the maps' own visibility error.
