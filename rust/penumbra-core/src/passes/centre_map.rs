//! Pass 1 of every method but `reference`: the shadow map from the light
//! centre, as a method's shadow-map settings ([`ShadowMapSettings`]) ask for
//! it, through the pass cache.

use std::sync::Arc;

use crate::error::Result;
use crate::frame::{Frame, FrameContext, Intermediate};
use crate::gpu::pool::PooledTexture;
use crate::light_frustum::LightProjection;
use crate::pass_cache::{CachedPass, PassKey};
use crate::passes::shadow_map::ShadowMapPass;
use crate::passes::shadow_test::ShadowMapSettings;

/// The shadow map from the light centre, as the pass cache keeps it (pass 1
/// of every method but `reference`; see [`centre_map()`]).
pub const CENTRE_MAP: CachedPass = CachedPass { name: "shadow_map", capacity: 3 };

/// Pass 1 of every method but `reference`: the shadow map from the light
/// centre over the projection `settings.projection` asks for, storing the
/// surface `settings.bias` asks for; reused from the pass cache when the
/// geometry, the projection, the map size and the stored surface are
/// unchanged. Returns the map and its projection. Sets the stats
/// `shadow_maps_rendered`, `map_size`, `cube_map` (1 for cube faces) and
/// `shadow_map_faces` (faces rendered), and the intermediate `shadow_map`
/// (one image per layer).
pub fn centre_map(frame: &mut Frame<'_>, settings: &ShadowMapSettings) -> Result<(PooledTexture, Arc<LightProjection>)> {
    settings.check_limits(frame.ctx.max_texture_side())?;
    let projection = frame.ctx.projection(settings.projection)?;
    let map_depth = settings.bias.map_depth();
    let key = centre_map_key(&frame.ctx, settings, &projection);
    let mut rendered = 0;
    let map = frame.cached(CENTRE_MAP.name, key, |frame| {
        let map = ShadowMapPass::create_map(&frame.ctx, settings.map_size, projection.layers());
        frame.pass(CENTRE_MAP.name, |ctx, encoder, ts| {
            ShadowMapPass::shared(ctx.device, ctx.pool).record(ctx, encoder, &map, &projection, map_depth, ts, (true, true))
        })?;
        rendered = 1;
        Ok(map)
    })?;
    frame.stat("shadow_maps_rendered", rendered);
    frame.stat("map_size", settings.map_size as i64);
    frame.stat("non_casters", frame.ctx.non_casters() as i64);
    frame.stat("cube_map", i64::from(projection.is_cube()));
    frame.stat("shadow_map_faces", projection.active_faces() as i64);
    frame.intermediate(Intermediate::depth("shadow_map", &map.resource.texture, projection.far()))?;
    Ok((map, projection))
}

/// The centre map's pass-cache key: it reads the geometry (the triangles that
/// cast a shadow, which the light's radius decides too), the projection, the
/// map's size and which surface it keeps.
pub fn centre_map_key(ctx: &FrameContext<'_>, settings: &ShadowMapSettings, projection: &LightProjection) -> PassKey {
    PassKey::new(CENTRE_MAP.name)
        .bytes(&ctx.geometry)
        .u32(ctx.non_casters() as u32)
        .projection(projection)
        .u32(settings.map_size)
        .bytes(format!("{:?}", settings.bias.map_depth()).as_bytes())
        .finish()
}
