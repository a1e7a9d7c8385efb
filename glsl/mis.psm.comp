// variant: mis.comp PSM_VISIBILITY
// mis with `--visibility psm`: the CDF samples are the frame's shared VPL set with shadow-map
// visibility, the gathering samples keep the voxel march (see mis.comp).
