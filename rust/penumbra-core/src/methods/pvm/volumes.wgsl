#import passes/light_ids.wgsl

// PVM pass 2 (Cournia 4.1.3): render the penumbra volumes' quadrilaterals
// from the light into the penumbra volume map: the penumbra volume depth map
// (PVDM, linear light depth / far, first-depth volume) and the penumbra
// volume edge map, in one pass.
//
// Departure from 4.1.3: the paper's two edge maps (PVEMs) hold the end
// points h0 and h1 of the silhouette edge that gave rise to the volume (six
// floats per texel, 16-bit there, 32-bit here). This map holds the edge's
// index + 1 (0 where no volume) and the visibility pass reads h0 and h1 from
// a buffer of the edges: the same information, 4 bytes per texel instead of
// 32. On a software rasteriser the pass's cost is the bytes it clears and
// writes (docs/real_meshes.md).
//
// The raster itself is passes/light_ids.wgsl, with the edge's index as the id.
