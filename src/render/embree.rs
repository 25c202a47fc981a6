//! Intel Embree 3, the ray-tracing kernels Mitsuba 3 traces with on the
//! CPU, loaded at run time. When `libembree3.so.3` is on the system
//! (Debian and Ubuntu: `libembree3-3`), a scene's triangles are traced by
//! it; without it, by obvhs ([`super::accel`]). Nothing links against it,
//! so one wheel serves both.
//!
//! The environment variable `MCSAMPLE_RAY_TRACER`, read when a scene is
//! built, chooses: `embree` (an error when the library cannot be
//! loaded), `obvhs`, or `auto` / unset (Embree when it loads).
//!
//! The structures passed to Embree are restated from its 3.13 headers as
//! Debian builds them (one instance level, no minimum width): only
//! version 3.13 and later 3.x are used. Embree's device and the TBB
//! threads it builds with belong to the process that loaded it: a process
//! forked after that traces with obvhs. Every call into Embree is
//! `unsafe`, each with the argument that makes it sound.

use std::ffi::{c_char, c_void};
use std::sync::{Arc, OnceLock};

use libloading::Library;

use super::accel::Hit;
use super::mesh::Mesh;
use super::shape::Ray;
use crate::error::{Error, Result};

/// The names tried, in order.
const LIBRARIES: [&str; 2] = ["libembree3.so.3", "libembree3.so"];

/// The variable that chooses the ray tracer.
pub const VARIABLE: &str = "MCSAMPLE_RAY_TRACER";

type Handle = *mut c_void;

/// `RTCIntersectContext` of Embree 3.13 as Debian builds it (one instance
/// level, no minimum width).
#[repr(C)]
struct Context {
    flags: u32,
    filter: *const c_void,
    inst_id: [u32; 1],
}

/// `RTCRay`.
#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct RtcRay {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: u32,
    id: u32,
    flags: u32,
}

/// `RTCHit`.
#[repr(C, align(16))]
struct RtcHit {
    ng: [f32; 3],
    u: f32,
    v: f32,
    prim_id: u32,
    geom_id: u32,
    inst_id: [u32; 1],
}

/// `RTCRayHit`.
#[repr(C)]
struct RayHit {
    ray: RtcRay,
    hit: RtcHit,
}

/// `RTC_INVALID_GEOMETRY_ID`.
const INVALID: u32 = u32::MAX;
/// `RTC_ERROR_OUT_OF_MEMORY`.
const OUT_OF_MEMORY: u32 = 4;

/// The entry points used, and the device every scene is made on.
struct Api {
    version: String,
    /// The process that loaded it.
    pid: u32,
    device: Handle,
    device_error: unsafe extern "C" fn(Handle) -> u32,
    new_scene: unsafe extern "C" fn(Handle) -> Handle,
    set_scene_flags: unsafe extern "C" fn(Handle, u32),
    set_build_quality: unsafe extern "C" fn(Handle, u32),
    new_geometry: unsafe extern "C" fn(Handle, u32) -> Handle,
    shared_buffer: unsafe extern "C" fn(Handle, u32, u32, u32, *const c_void, usize, usize, usize),
    commit_geometry: unsafe extern "C" fn(Handle),
    attach_geometry: unsafe extern "C" fn(Handle, Handle) -> u32,
    release_geometry: unsafe extern "C" fn(Handle),
    commit_scene: unsafe extern "C" fn(Handle),
    release_scene: unsafe extern "C" fn(Handle),
    intersect1: unsafe extern "C" fn(Handle, *mut Context, *mut RayHit),
    intersect1m: unsafe extern "C" fn(Handle, *mut Context, *mut RayHit, u32, usize),
    occluded1: unsafe extern "C" fn(Handle, *mut Context, *mut RtcRay),
    occluded1m: unsafe extern "C" fn(Handle, *mut Context, *mut RtcRay, u32, usize),
    /// Kept loaded for the process's life: the pointers above point into it.
    _library: Library,
}

// SAFETY: Embree's device and committed scenes may be used from any
// thread at once (its API's documented thread safety); the function
// pointers are plain code addresses.
#[allow(unsafe_code)]
unsafe impl Send for Api {}
#[allow(unsafe_code)]
unsafe impl Sync for Api {}

impl Api {
    /// Loads the library and makes a device, or says why not.
    #[allow(unsafe_code)]
    fn load() -> std::result::Result<Api, String> {
        // SAFETY: loading a shared library runs its initialisers: Embree's
        // are its own static constructors, safe to run at any time.
        let library = LIBRARIES
            .iter()
            .find_map(|name| unsafe { Library::new(name) }.ok())
            .ok_or_else(|| format!("{} not found", LIBRARIES[0]))?;
        macro_rules! entry {
            ($name:literal) => {
                // SAFETY: the symbol has the C signature of Embree 3's
                // header, which the field's type restates.
                *unsafe { library.get(concat!($name, "\0").as_bytes()) }
                    .map_err(|e| format!("{}: {e}", $name))?
            };
        }
        let new_device: unsafe extern "C" fn(*const c_char) -> Handle = entry!("rtcNewDevice");
        let property: unsafe extern "C" fn(Handle, u32) -> isize = entry!("rtcGetDeviceProperty");
        // SAFETY: a null configuration string is Embree's default.
        let device = unsafe { new_device(std::ptr::null()) };
        if device.is_null() {
            return Err("rtcNewDevice failed (an unsupported CPU?)".into());
        }
        // RTC_DEVICE_PROPERTY_VERSION (0): major * 10000 + minor * 100 + patch.
        // SAFETY: a valid device and property.
        let v = unsafe { property(device, 0) };
        if !(31300..40000).contains(&v) {
            return Err(format!("version {v} is not 3.13 or a later 3.x"));
        }
        Ok(Api {
            version: format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100),
            pid: std::process::id(),
            device,
            device_error: entry!("rtcGetDeviceError"),
            new_scene: entry!("rtcNewScene"),
            set_scene_flags: entry!("rtcSetSceneFlags"),
            set_build_quality: entry!("rtcSetSceneBuildQuality"),
            new_geometry: entry!("rtcNewGeometry"),
            shared_buffer: entry!("rtcSetSharedGeometryBuffer"),
            commit_geometry: entry!("rtcCommitGeometry"),
            attach_geometry: entry!("rtcAttachGeometry"),
            release_geometry: entry!("rtcReleaseGeometry"),
            commit_scene: entry!("rtcCommitScene"),
            release_scene: entry!("rtcReleaseScene"),
            intersect1: entry!("rtcIntersect1"),
            intersect1m: entry!("rtcIntersect1M"),
            occluded1: entry!("rtcOccluded1"),
            occluded1m: entry!("rtcOccluded1M"),
            _library: library,
        })
    }

    /// The library, loaded on first use, or why it could not be.
    fn get() -> std::result::Result<&'static Api, &'static str> {
        static API: OnceLock<std::result::Result<Api, String>> = OnceLock::new();
        let api = API
            .get_or_init(Api::load)
            .as_ref()
            .map_err(String::as_str)?;
        if api.pid != std::process::id() {
            return Err("it was loaded before this process was forked");
        }
        Ok(api)
    }

    /// The device's pending error, as [`Error`] (`what` being built).
    #[allow(unsafe_code)]
    fn check(&self, what: &str, bytes: u128) -> Result<()> {
        // SAFETY: a valid device.
        match unsafe { (self.device_error)(self.device) } {
            0 => Ok(()),
            OUT_OF_MEMORY => Err(Error::Memory {
                what: "Embree's BVH",
                bytes,
            }),
            code => Err(Error::Argument {
                arg: "scene",
                message: format!("Embree failed to build {what} (RTCError {code})"),
            }),
        }
    }
}

/// Embree 3, loaded, as [`wanted`] hands it out for [`Triangles::new`].
#[derive(Clone, Copy)]
pub struct Library3(&'static Api);

/// The ray tracer `MCSAMPLE_RAY_TRACER` asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Choice {
    Auto,
    Embree,
    Obvhs,
}

fn choice() -> Result<Choice> {
    match std::env::var(VARIABLE).as_deref() {
        Err(_) | Ok("" | "auto") => Ok(Choice::Auto),
        Ok("embree") => Ok(Choice::Embree),
        Ok("obvhs") => Ok(Choice::Obvhs),
        Ok(other) => Err(Error::Argument {
            arg: VARIABLE,
            message: format!("{VARIABLE} = {other:?}: must be \"embree\", \"obvhs\" or \"auto\""),
        }),
    }
}

/// The Embree library when the scenes built now should use it: `None`
/// under `obvhs`, or under `auto` without the library. Every scene's build
/// asks, whether it has triangles or not, so that a wrong setting is
/// always an error.
///
/// # Errors
/// [`Error::Argument`] for an unknown `MCSAMPLE_RAY_TRACER`, or when it
/// asks for `embree` and the library does not load.
pub fn wanted() -> Result<Option<Library3>> {
    match choice()? {
        Choice::Obvhs => Ok(None),
        Choice::Auto => Ok(Api::get().ok().map(Library3)),
        Choice::Embree => Api::get()
            .map(|a| Some(Library3(a)))
            .map_err(|why| Error::Argument {
                arg: VARIABLE,
                message: format!("{VARIABLE} = \"embree\", but Embree 3 cannot be loaded: {why}"),
            }),
    }
}

/// The working memory of [`Triangles::intersect_many`] and
/// [`Triangles::occluded_many`]: Embree's records of a stream of rays, kept
/// from one batch to the next.
#[derive(Default)]
pub struct Stream {
    hits: Vec<RayHit>,
    rays: Vec<RtcRay>,
}

/// Rays per call of a stream function (its count is a `u32`).
const STREAM_CHUNK: usize = 1 << 20;

/// Triangle meshes in an Embree scene (one geometry each, tracing the
/// meshes' own vertex and index buffers, which it keeps), with the number
/// of each one's first face in the scene's list of primitives, by geometry
/// ID.
pub struct Triangles {
    api: &'static Api,
    scene: Handle,
    first: Vec<u32>,
    /// Kept as long as the scene, which reads their buffers.
    _meshes: Arc<[Mesh]>,
}

// SAFETY: a committed Embree scene is read-only and may be traced from
// any thread (see `Api`).
#[allow(unsafe_code)]
unsafe impl Send for Triangles {}
#[allow(unsafe_code)]
unsafe impl Sync for Triangles {}

impl Drop for Triangles {
    #[allow(unsafe_code)]
    fn drop(&mut self) {
        // SAFETY: the scene was made by `new` (not null) and is released
        // once.
        unsafe { (self.api.release_scene)(self.scene) }
    }
}

impl Triangles {
    /// The faces of `meshes` in an Embree scene of `library` (which reads
    /// the meshes' vertices and faces where they are, and keeps them); the
    /// faces of mesh `m` are the scene's primitives from `first[m]` on.
    ///
    /// # Errors
    /// [`Error::Memory`] when the memory cannot be had or Embree runs out
    /// of it; [`Error::Argument`] when Embree fails otherwise.
    ///
    /// # Panics
    /// If `first` is not one number per mesh.
    #[allow(unsafe_code)]
    pub fn new(library: Library3, meshes: &Arc<[Mesh]>, first: &[u32]) -> Result<Self> {
        const WHAT: &str = "Embree's BVH";
        let api = library.0;
        assert_eq!(first.len(), meshes.len(), "a first face for every mesh");
        let n: usize = meshes.iter().map(|m| m.faces().len()).sum();
        // About what Embree allocates: a BVH of some 100 bytes a triangle,
        // as it goes, so check first.
        let bytes = n as u128 * 128;
        crate::alloc::probe::<u8>(n.saturating_mul(128), WHAT)?;
        let traced = || {
            meshes
                .iter()
                .zip(first)
                .filter(|(m, _)| !m.faces().is_empty())
        };
        let mut firsts = crate::alloc::with_capacity(traced().count(), WHAT)?;
        // SAFETY: calls on a valid device, in the order Embree's API
        // requires (buffers set before the geometry is committed,
        // attached, released; the scene committed before it is traced).
        // The buffers shared are a mesh's: its vertices 16 bytes apart
        // (each readable as 16 bytes, as Embree reads them) and its faces,
        // triples of indices of its vertices (as `Mesh::new` makes them);
        // the scene keeps the meshes, which nothing changes.
        unsafe {
            let scene = (api.new_scene)(api.device);
            if scene.is_null() {
                api.check("a scene", bytes)?;
                return Err(Error::Memory { what: WHAT, bytes });
            }
            let mut triangles = Triangles {
                api,
                scene,
                first: Vec::new(),
                _meshes: Arc::clone(meshes),
            };
            api.check("a scene", bytes)?;
            // RTC_SCENE_FLAG_ROBUST: no optimisation that could let a ray
            // slip between two triangles sharing an edge.
            (api.set_scene_flags)(scene, 1 << 2);
            // RTC_BUILD_QUALITY_HIGH: a scene is built once and traced
            // billions of times.
            (api.set_build_quality)(scene, 2);
            for (mesh, &first) in traced() {
                let geometry = (api.new_geometry)(api.device, 0);
                if geometry.is_null() {
                    api.check("a triangle mesh", bytes)?;
                    return Err(Error::Memory { what: WHAT, bytes });
                }
                // RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT3.
                (api.shared_buffer)(
                    geometry,
                    1,
                    0,
                    0x9003,
                    mesh.points().as_ptr().cast(),
                    0,
                    size_of::<glam::Vec3A>(),
                    mesh.points().len(),
                );
                // RTC_BUFFER_TYPE_INDEX, RTC_FORMAT_UINT3.
                (api.shared_buffer)(
                    geometry,
                    0,
                    0,
                    0x5003,
                    mesh.faces().as_ptr().cast(),
                    0,
                    size_of::<[u32; 3]>(),
                    mesh.faces().len(),
                );
                (api.commit_geometry)(geometry);
                let id = (api.attach_geometry)(scene, geometry);
                (api.release_geometry)(geometry);
                api.check("a triangle mesh", bytes)?;
                // IDs are handed out from 0 in order of attachment.
                if id as usize != firsts.len() {
                    return Err(Error::Argument {
                        arg: "scene",
                        message: format!("Embree numbered mesh {} as {id}", firsts.len()),
                    });
                }
                firsts.push(first);
            }
            (api.commit_scene)(scene);
            api.check("the BVH", bytes)?;
            triangles.first = firsts;
            Ok(triangles)
        }
    }

    /// `"embree"` and the library's version, as `"embree 3.13.5"`.
    pub fn name(&self) -> String {
        format!("embree {}", self.api.version)
    }

    /// `ray` for Embree, which keeps hits at `t ≤ tfar`: `tfar` is the
    /// float below `ray.tmax`, as the other primitives' tests keep `t <
    /// tmax`.
    fn ray(ray: &Ray) -> RtcRay {
        RtcRay {
            org: ray.o.to_array(),
            tnear: 0.0,
            dir: ray.d.to_array(),
            time: 0.0,
            tfar: ray.tmax.next_down(),
            mask: u32::MAX,
            id: 0,
            flags: 0,
        }
    }

    /// `rtcInitIntersectContext`'s context (no filter), for rays that are
    /// `coherent` or not.
    fn context(coherent: bool) -> Context {
        Context {
            flags: u32::from(coherent),
            filter: std::ptr::null(),
            inst_id: [INVALID],
        }
    }

    /// `ray` with no hit yet, for `rtcIntersect`.
    fn ray_hit(ray: &Ray) -> RayHit {
        RayHit {
            ray: Self::ray(ray),
            hit: RtcHit {
                ng: [0.0; 3],
                u: 0.0,
                v: 0.0,
                prim_id: INVALID,
                geom_id: INVALID,
                inst_id: [INVALID],
            },
        }
    }

    /// The hit Embree left in `rh`, if any.
    #[inline]
    fn hit_of(&self, rh: &RayHit) -> Option<Hit> {
        (rh.hit.geom_id != INVALID).then(|| Hit {
            t: rh.ray.tfar,
            primitive: self.first[rh.hit.geom_id as usize] + rh.hit.prim_id,
            bary: [rh.hit.u, rh.hit.v],
        })
    }

    /// The nearest hit of `ray` in `[0, ray.tmax)`: the primitive, the
    /// distance and the barycentrics `(b1, b2)` of `p0 + b1 e1 + b2 e2`.
    #[inline]
    #[allow(unsafe_code)]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut rh = Self::ray_hit(ray);
        let mut context = Self::context(false);
        // SAFETY: a committed scene, a context and a ray-hit laid out as
        // Embree's header declares them.
        unsafe { (self.api.intersect1)(self.scene, &mut context, &mut rh) };
        self.hit_of(&rh)
    }

    /// [`Triangles::intersect`] of each ray of `rays`, appended to `out`:
    /// traced as one stream (`rtcIntersect1M`), which Embree splits into
    /// packets when the rays are `coherent` (as the camera rays of a pixel
    /// are).
    ///
    /// # Errors
    /// [`Error::Memory`] when the stream's records cannot be had.
    #[allow(unsafe_code)]
    pub fn intersect_many(
        &self,
        rays: &[Ray],
        coherent: bool,
        stream: &mut Stream,
        out: &mut Vec<Option<Hit>>,
    ) -> Result<()> {
        const WHAT: &str = "a stream of rays";
        stream.hits.clear();
        crate::alloc::reserve(&mut stream.hits, rays.len(), WHAT)?;
        crate::alloc::reserve(out, rays.len(), WHAT)?;
        stream.hits.extend(rays.iter().map(Self::ray_hit));
        let mut context = Self::context(coherent);
        for chunk in stream.hits.chunks_mut(STREAM_CHUNK) {
            // SAFETY: as in `intersect`, for `chunk.len()` records one
            // `size_of::<RayHit>()` apart (aligned to 16, as Embree needs).
            unsafe {
                (self.api.intersect1m)(
                    self.scene,
                    &mut context,
                    chunk.as_mut_ptr(),
                    chunk.len() as u32,
                    size_of::<RayHit>(),
                )
            };
        }
        out.extend(stream.hits.iter().map(|rh| self.hit_of(rh)));
        Ok(())
    }

    /// [`Triangles::occluded`] of each ray of `rays` (incoherent ones: the
    /// shadow rays of a batch of paths), appended to `out`, as one stream
    /// (`rtcOccluded1M`).
    ///
    /// # Errors
    /// [`Error::Memory`] when the stream's records cannot be had.
    #[allow(unsafe_code)]
    pub fn occluded_many(
        &self,
        rays: &[Ray],
        stream: &mut Stream,
        out: &mut Vec<bool>,
    ) -> Result<()> {
        const WHAT: &str = "a stream of shadow rays";
        stream.rays.clear();
        crate::alloc::reserve(&mut stream.rays, rays.len(), WHAT)?;
        crate::alloc::reserve(out, rays.len(), WHAT)?;
        stream.rays.extend(rays.iter().map(Self::ray));
        let mut context = Self::context(false);
        for chunk in stream.rays.chunks_mut(STREAM_CHUNK) {
            // SAFETY: as in `occluded`, for `chunk.len()` records one
            // `size_of::<RtcRay>()` apart (aligned to 16, as Embree needs).
            unsafe {
                (self.api.occluded1m)(
                    self.scene,
                    &mut context,
                    chunk.as_mut_ptr(),
                    chunk.len() as u32,
                    size_of::<RtcRay>(),
                )
            };
        }
        out.extend(stream.rays.iter().map(|r| r.tfar == f32::NEG_INFINITY));
        Ok(())
    }

    /// Whether a triangle lies on `ray` in `[0, ray.tmax)`.
    #[inline]
    #[allow(unsafe_code)]
    pub fn occluded(&self, ray: &Ray) -> bool {
        let mut r = Self::ray(ray);
        let mut context = Self::context(false);
        // SAFETY: as in `intersect`.
        unsafe { (self.api.occluded1)(self.scene, &mut context, &mut r) };
        r.tfar == f32::NEG_INFINITY
    }
}
