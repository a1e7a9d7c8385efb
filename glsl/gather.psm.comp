// variant: gather.comp PSM_VISIBILITY
// gather with `--visibility psm`: the frame's shared VPL set, visibility from each VPL's paraboloid
// shadow map (see gather.comp and psm.comp).
