//! A glTF file's animation in the window: the clip playing, the time it stands at, its speed,
//! paused or not (the flags start it, the panel changes it), and its pose set on the renderer
//! when the time or clip changed (not while paused, so kept shadow maps stay kept).

use anyhow::{bail, Result};
use manyshadows::scene::animation::Playing;
use manyshadows::scene::Scene;
use manyshadows::Renderer;

use crate::view::args::ViewArgs;

/// Where the file's animation stands.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Player {
    pub(super) playing: Playing,
    /// Seconds into the clip (within its duration).
    pub(super) time: f32,
    /// Seconds of animation per second shown.
    pub(super) speed: f32,
    pub(super) paused: bool,
    /// The clip and time last set on the renderer (`None`: set it at the next frame).
    applied: Option<(Playing, f32)>,
}

/// Fastest playback the flag and the panel allow.
pub(super) const MAX_SPEED: f32 = 8.0;

impl Player {
    /// The player the flags ask for on `scene` (`None`: nothing moves); the animation flags
    /// on a scene without animations, an animation not in the file and bad numbers are
    /// refused by name.
    pub(super) fn new(scene: &Scene, args: &ViewArgs) -> Result<Option<Player>> {
        let anims = &scene.animations;
        if !args.speed.is_finite() || !(0.0..=MAX_SPEED).contains(&args.speed) {
            bail!("--speed {}: must be from 0 to {MAX_SPEED}", args.speed);
        }
        if anims.is_empty() {
            for (flag, given) in [
                ("--animation", args.animation.is_some()),
                ("--time", args.time.is_some()),
                ("--paused", args.paused),
                ("--speed", args.speed != 1.0),
            ] {
                if given {
                    bail!(
                        "{flag}: scene {} has no animation that moves a mesh (a glTF file's \
                         node animations play; --animate moves a caster of any scene)",
                        scene.name
                    );
                }
            }
            return Ok(None);
        }
        if args.animate {
            bail!("--animate: the file's own animation moves the scene (see --animation)");
        }
        let playing = match &args.animation {
            Some(a) => anims
                .choose(a)
                .map_err(|e| anyhow::anyhow!("--animation {a}: {e}"))?,
            None => Playing::One(0),
        };
        let time = args.time.unwrap_or(0.0);
        if !time.is_finite() || time < 0.0 {
            bail!("--time {time}: must be a finite number of seconds, 0 or more");
        }
        Ok(Some(Player {
            playing,
            time: anims.wrap(playing, time),
            speed: args.speed,
            paused: args.paused,
            applied: None,
        }))
    }

    /// `dt` seconds later, unless paused; looping at the clip's end.
    pub(super) fn advance(&mut self, scene: &Scene, dt: f32) {
        if !self.paused {
            let d = scene.animations.duration(self.playing);
            let t = self.time + dt * self.speed;
            self.time = if d > 0.0 { t % d } else { 0.0 };
        }
    }

    /// The pose at the current time set on `renderer`, if the clip or time changed since the
    /// last; an error is the renderer's words.
    pub(super) fn apply(&mut self, renderer: &mut Renderer) -> Result<()> {
        if self.applied == Some((self.playing, self.time)) {
            return Ok(());
        }
        renderer.set_time(self.playing, self.time)?;
        self.applied = Some((self.playing, self.time));
        Ok(())
    }

    /// A new renderer stands at the scene as loaded: set the pose again at the next frame.
    pub(super) fn forget(&mut self) {
        self.applied = None;
    }
}
