// variant: mis.comp PSM_VISIBILITY PSM_EXACT EXACT_VISIBILITY
// mis with `--visibility psm-exact`: the CDF samples are the frame's shared VPL set, both strategies
// with exact shadow rays (see mis.comp).
