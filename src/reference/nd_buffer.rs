//! An ND-buffer on the CPU, and the camera that rendered it: the CPU twin of
//! `shaders/nd_buffer.wgsl`.

use bevy::math::{IVec2, Mat4, Vec3, Vec4, Vec4Swizzles};

/// One ND-buffer texel: world-space unit normal (zero where nothing was drawn) and reverse-Z
/// depth (0 where nothing was drawn).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NdTexel {
    /// World-space unit normal.
    pub normal: Vec3,
    /// Reverse-Z depth (1 = near plane, 0 = infinitely far or empty).
    pub depth: f32,
}

impl NdTexel {
    /// From an `Rgba32Float` read-back texel (`AoReadback` layout).
    pub fn from_rgba(rgba: [f32; 4]) -> Self {
        Self {
            normal: Vec3::new(rgba[0], rgba[1], rgba[2]),
            depth: rgba[3],
        }
    }
}

/// The matrices of a view, as Bevy's view uniform holds them.
#[derive(Clone, Copy, Debug)]
pub struct ViewMatrices {
    /// Clip space to world space.
    pub world_from_clip: Mat4,
    /// World space to view space.
    pub view_from_world: Mat4,
    /// The projection (view space to clip space).
    pub clip_from_view: Mat4,
}

impl ViewMatrices {
    /// From a camera's world transform and projection matrix.
    pub fn new(world_from_view: Mat4, clip_from_view: Mat4) -> Self {
        Self {
            world_from_clip: world_from_view * clip_from_view.inverse(),
            view_from_world: world_from_view.inverse(),
            clip_from_view,
        }
    }

    /// How fully the camera sees a face with unit normal `f` at world point `x`, as `seen_face`
    /// in `spheres/splat.wgsl`: |cos| of the angle between `f` and the direction to the eye
    /// (the view's backward axis when orthographic), over 0.3, at most 1.
    pub fn seen_face(&self, x: Vec3, f: Vec3) -> f32 {
        let world_from_view = self.view_from_world.inverse();
        let to_eye = if self.clip_from_view.w_axis.w == 1.0 {
            world_from_view.z_axis.truncate()
        } else {
            world_from_view.w_axis.truncate() - x
        };
        (to_eye.normalize_or_zero().dot(f).abs() / 0.3).clamp(0.0, 1.0)
    }

    /// World position of the centre of pixel (x, y) of a `width`×`height` viewport at
    /// reverse-Z `depth`.
    pub fn world_position(&self, x: i32, y: i32, width: u32, height: u32, depth: f32) -> Vec3 {
        let u = (x as f32 + 0.5) / width as f32;
        let v = (y as f32 + 0.5) / height as f32;
        let world = self.world_from_clip * Vec4::new(u * 2.0 - 1.0, 1.0 - v * 2.0, depth, 1.0);
        world.xyz() / world.w
    }

    /// View-space position of the centre of pixel (x, y) at reverse-Z `depth`.
    pub fn view_position(&self, x: i32, y: i32, width: u32, height: u32, depth: f32) -> Vec3 {
        let u = (x as f32 + 0.5) / width as f32;
        let v = (y as f32 + 0.5) / height as f32;
        self.view_position_at(u, v, depth)
    }

    /// View-space position at viewport coordinates (u, v) (0..1, v down) and reverse-Z `depth`.
    pub fn view_position_at(&self, u: f32, v: f32, depth: f32) -> Vec3 {
        let p = self.clip_from_view.inverse() * Vec4::new(u * 2.0 - 1.0, 1.0 - v * 2.0, depth, 1.0);
        p.xyz() / p.w
    }

    /// Distance in front of the camera along its view axis (metres).
    pub fn view_depth(&self, world_position: Vec3) -> f32 {
        -(self.view_from_world * world_position.extend(1.0)).z
    }

    /// World-space height of one pixel at view depth `depth` (metres).
    pub fn pixel_world_size(&self, depth: f32, height: u32) -> f32 {
        let p11 = self.clip_from_view.y_axis.y;
        if self.clip_from_view.w_axis.w == 1.0 {
            2.0 / (p11 * height as f32)
        } else {
            2.0 * depth / (p11 * height as f32)
        }
    }
}

/// The surface one pixel of the front layer shows, as `receiver` in
/// `shaders/image_space_bindings.wgsl` finds it for the image-space techniques.
#[derive(Clone, Copy, Debug)]
pub struct Receiver {
    /// Its pixel.
    pub pixel: IVec2,
    /// Its front-layer texel: world-space unit normal and reverse-Z depth.
    pub texel: NdTexel,
    /// Its position, world space (metres).
    pub world_position: Vec3,
    /// Its position, view space (metres).
    pub view_position: Vec3,
    /// Its unit normal, view space.
    pub view_normal: Vec3,
}

/// Both layers of an ND-buffer, row-major, top row first.
#[derive(Clone, Debug)]
pub struct NdBuffer {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// Front layer (Bevy's prepass).
    pub front: Vec<NdTexel>,
    /// Back-face layer.
    pub back: Vec<NdTexel>,
}

impl NdBuffer {
    /// How far the ND-buffer already holds the geometry at world point `x`, exactly as
    /// `nd_buffer_holds` in `shaders/nd_buffer.wgsl` decides it: 1 on screen and no deeper than
    /// the pixel's first solid interval (front layer, or back layer with `use_back`) plus
    /// `tolerance`, 0 off-screen or deeper, a ramp over a second `tolerance`.
    pub fn holds(&self, view: &ViewMatrices, use_back: bool, x: Vec3, tolerance: f32) -> f32 {
        let clip = view.clip_from_view * view.view_from_world * x.extend(1.0);
        if clip.w <= 0.0 {
            return 0.0;
        }
        let ndc = clip.xy() / clip.w;
        if ndc.x.abs() >= 1.0 || ndc.y.abs() >= 1.0 {
            return 0.0;
        }
        let (w, h) = (self.width as f32, self.height as f32);
        let px = (((ndc.x * 0.5 + 0.5) * w) as i32).min(self.width as i32 - 1);
        let py = (((0.5 - ndc.y * 0.5) * h) as i32).min(self.height as i32 - 1);
        let Some(front) = self.texel(false, px, py) else {
            return 0.0;
        };
        if front.depth <= 0.0 {
            return 1.0;
        }
        let mut deepest = front.depth;
        if use_back
            && let Some(back) = self.texel(true, px, py)
            && back.depth > 0.0
        {
            deepest = deepest.min(back.depth);
        }
        let surface =
            view.view_depth(view.world_position(px, py, self.width, self.height, deepest));
        let beyond = view.view_depth(x) - surface - tolerance;
        1.0 - (beyond / tolerance.max(1e-6)).clamp(0.0, 1.0)
    }

    /// The surface pixel (x, y) of the front layer shows; `None` outside the image and on the
    /// background (no depth or no normal), where every technique writes "open".
    pub fn receiver(&self, view: &ViewMatrices, x: i32, y: i32) -> Option<Receiver> {
        let texel = self
            .texel(false, x, y)
            .filter(|t| t.depth > 0.0 && t.normal != Vec3::ZERO)?;
        Some(Receiver {
            pixel: IVec2::new(x, y),
            texel,
            world_position: view.world_position(x, y, self.width, self.height, texel.depth),
            view_position: view.view_position(x, y, self.width, self.height, texel.depth),
            view_normal: (view.view_from_world * texel.normal.extend(0.0))
                .xyz()
                .normalize(),
        })
    }

    /// `f(x, y)` of every pixel, row-major.
    pub fn per_pixel<T>(&self, mut f: impl FnMut(i32, i32) -> T) -> Vec<T> {
        (0..self.width * self.height)
            .map(|i| f((i % self.width) as i32, (i / self.width) as i32))
            .collect()
    }

    /// `shade` of every receiver of the front layer, row-major; the default value (open) on
    /// the background.
    pub fn per_receiver<T: Default>(
        &self,
        view: &ViewMatrices,
        mut shade: impl FnMut(&Receiver) -> T,
    ) -> Vec<T> {
        self.per_pixel(|x, y| {
            self.receiver(view, x, y)
                .map(|r| shade(&r))
                .unwrap_or_default()
        })
    }

    /// The texel of a layer at (x, y); `None` outside the image.
    pub fn texel(&self, back: bool, x: i32, y: i32) -> Option<NdTexel> {
        if x < 0 || y < 0 || x >= self.width as i32 || y >= self.height as i32 {
            return None;
        }
        let layer = if back { &self.back } else { &self.front };
        layer
            .get(y as usize * self.width as usize + x as usize)
            .copied()
    }
}
