//! `mcsample._core.render`: the scene builder, the compiled scene and the
//! render call (GIL released, progress reported, Ctrl-C honoured).

use crate::python::Obj;
use std::sync::Arc;
use std::sync::mpsc;
use std::time::Duration;

use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use glam::Vec3A;

use super::args::{choice, depth_arg, heuristic_arg, index_arg, seed_arg};
use super::arrays::{Check, Points};
use super::batch::map_pair;
use super::envmap::PyEnvMap;
use super::error::guarded;
use super::phong::PyPhong;
use crate::alloc;
use crate::error::Error;
use crate::render::camera::{Camera, FovAxis};
use crate::render::film::{self, Block};
use crate::render::filter::Filter;
use crate::render::mesh::Mesh;
use crate::render::motion::Motion;
use crate::render::scene::daffine;
use crate::render::scene::{Environment, Geometry, Material, Shape, affine};
use crate::render::{Integrator, Progress, Samples, Scene, Settings, Strategy};
use crate::sampler::Sampler;

fn rows<'py, T: numpy::Element + Copy, const K: usize>(
    a: &PyReadonlyArray2<'py, T>,
    arg: &'static str,
) -> PyResult<Vec<[T; K]>> {
    let view = a.as_array();
    if view.ncols() != K {
        return Err(Error::Shape {
            arg,
            expected: format!("(N, {K})"),
            got: crate::error::shape_str(view.shape()),
        }
        .into());
    }
    Ok(alloc::collect(
        view.rows()
            .into_iter()
            .map(|r| std::array::from_fn(|k| r[k])),
        arg,
    )?)
}

/// Checks that every channel of the RGB radiance `value` (argument `arg`)
/// is finite and >= 0.
fn radiance_arg(arg: &'static str, value: [f64; 3], requirement: &str) -> PyResult<()> {
    match value.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
        Some(k) => Err(Error::Element {
            arg,
            index: format!("[{k}]"),
            value: value[k],
            requirement: requirement.into(),
        }
        .into()),
        None => Ok(()),
    }
}

/// Collects shapes, lights and the camera of a scene, then builds it
/// (``mcsample.Scene.from_mitsuba`` drives it; most users never call it).
#[pyclass(module = "mcsample._core.render", name = "SceneBuilder")]
#[derive(Default)]
pub struct PySceneBuilder {
    shapes: Vec<Shape>,
    environment: Option<Environment>,
    camera: Option<(Camera, usize, usize)>,
    filter: Option<(Filter, bool)>,
}

impl PySceneBuilder {
    fn push(
        &mut self,
        geometry: crate::Result<Geometry>,
        bsdf: &PyPhong,
        two_sided: bool,
        emission: Option<[f64; 3]>,
    ) -> PyResult<()> {
        if let Some(l) = emission {
            radiance_arg("emission", l, "radiance must be finite and >= 0")?;
        }
        self.shapes.push(Shape {
            geometry: geometry?,
            material: Material {
                bsdf: *bsdf.inner(),
                two_sided,
            },
            emission,
            motion: None,
        });
        Ok(())
    }

    fn set_environment(&mut self, env: Environment) -> PyResult<()> {
        if self.environment.is_some() {
            return Err(Error::Argument {
                arg: "environment",
                message: "a scene holds at most one environment emitter (envmap or constant)"
                    .into(),
            }
            .into());
        }
        self.environment = Some(env);
        Ok(())
    }
}

#[pymethods]
impl PySceneBuilder {
    #[new]
    fn new() -> Self {
        Self::default()
    }

    /// Adds a triangle mesh: ``vertices`` (N, 3) float64 in world space,
    /// ``faces`` (M, 3) int64, ``normals`` (N, 3) or None.
    #[pyo3(signature = (vertices, faces, normals, face_normals, bsdf, two_sided, emission))]
    #[allow(clippy::too_many_arguments)]
    fn add_mesh(
        &mut self,
        py: Python<'_>,
        vertices: PyReadonlyArray2<'_, f64>,
        faces: PyReadonlyArray2<'_, i64>,
        normals: Option<PyReadonlyArray2<'_, f64>>,
        face_normals: bool,
        bsdf: PyRef<'_, PyPhong>,
        two_sided: bool,
        emission: Option<[f64; 3]>,
    ) -> PyResult<()> {
        let v = rows::<f64, 3>(&vertices, "vertices")?;
        let f = rows::<i64, 3>(&faces, "faces")?;
        let n = normals
            .as_ref()
            .map(|n| rows::<f64, 3>(n, "normals"))
            .transpose()?;
        let geometry =
            py.detach(|| Mesh::new(&v, &f, n.as_deref(), face_normals).map(Geometry::Mesh));
        self.push(geometry, &bsdf, two_sided, emission)
    }

    /// Adds a sphere.
    #[pyo3(signature = (center, radius, flip_normals, bsdf, two_sided, emission))]
    fn add_sphere(
        &mut self,
        center: [f64; 3],
        radius: f64,
        flip_normals: bool,
        bsdf: PyRef<'_, PyPhong>,
        two_sided: bool,
        emission: Option<[f64; 3]>,
    ) -> PyResult<()> {
        let geometry = Geometry::sphere(center, radius, flip_normals);
        self.push(geometry, &bsdf, two_sided, emission)
    }

    /// Adds Mitsuba's unit disk placed by the row-major 4×4 ``to_world``.
    #[pyo3(signature = (to_world, bsdf, two_sided, emission))]
    fn add_disk(
        &mut self,
        to_world: [[f64; 4]; 4],
        bsdf: PyRef<'_, PyPhong>,
        two_sided: bool,
        emission: Option<[f64; 3]>,
    ) -> PyResult<()> {
        self.push(Geometry::disk(to_world), &bsdf, two_sided, emission)
    }

    /// Lights the scene with an environment map.
    fn set_envmap(&mut self, env: PyRef<'_, PyEnvMap>) -> PyResult<()> {
        self.set_environment(Environment::Map(Arc::clone(env.inner())))
    }

    /// Lights the scene with the same radiance from every direction.
    fn set_constant(&mut self, radiance: [f64; 3]) -> PyResult<()> {
        radiance_arg("radiance", radiance, "must be finite and >= 0")?;
        self.set_environment(Environment::Constant(radiance))
    }

    /// Sets the camera and the film size.
    #[pyo3(signature = (to_world, fov, fov_axis, width, height, near_clip, far_clip, aperture_radius, focus_distance))]
    #[allow(clippy::too_many_arguments)]
    fn set_camera(
        &mut self,
        to_world: [[f64; 4]; 4],
        fov: f64,
        fov_axis: &str,
        width: &Obj<'_>,
        height: &Obj<'_>,
        near_clip: f64,
        far_clip: f64,
        aperture_radius: f64,
        focus_distance: f64,
    ) -> PyResult<()> {
        let axis = choice(
            "fov_axis",
            fov_axis,
            &[
                ("x", FovAxis::X),
                ("y", FovAxis::Y),
                ("diagonal", FovAxis::Diagonal),
                ("smaller", FovAxis::Smaller),
                ("larger", FovAxis::Larger),
            ],
        )?;
        let width = index_arg(width, "width", 1, 1 << 15)? as usize;
        let height = index_arg(height, "height", 1, 1 << 15)? as usize;
        let camera = Camera::new(
            affine("to_world", to_world)?,
            fov,
            axis,
            width,
            height,
            near_clip,
            far_clip,
            aperture_radius,
            focus_distance,
        )?;
        self.camera = Some((camera, width, height));
        Ok(())
    }

    /// Moves the shape added last: its transform goes from ``start`` (where
    /// it was added, at ``shutter_open``) to ``end`` (at ``shutter_close``),
    /// both row-major 4×4.
    #[pyo3(signature = (start, end))]
    fn set_motion(&mut self, start: [[f64; 4]; 4], end: [[f64; 4]; 4]) -> PyResult<()> {
        let motion = Motion::new(
            "to_world_end",
            daffine("to_world", start)?,
            daffine("to_world_end", end)?,
        )?;
        let shape = self.shapes.last_mut().ok_or_else(|| Error::Argument {
            arg: "to_world_end",
            message: "no shape to move".into(),
        })?;
        shape.motion = Some(motion);
        Ok(())
    }

    /// Moves the camera: its ``to_world`` at ``shutter_close`` is ``end``
    /// (row-major 4×4; call after ``set_camera``).
    fn set_camera_motion(&mut self, end: [[f64; 4]; 4]) -> PyResult<()> {
        let end = daffine("to_world_end", end)?;
        let (camera, width, height) = self.camera.ok_or_else(|| Error::Argument {
            arg: "to_world_end",
            message: "set the camera first".into(),
        })?;
        self.camera = Some((camera.with_motion(end)?, width, height));
        Ok(())
    }

    /// Sets the film's reconstruction filter: ``"box"`` or ``"gaussian"``
    /// (of standard deviation ``stddev`` pixels), sampled on the film
    /// alone or, with ``sample_border``, on the film grown by the filter's
    /// border (Mitsuba's ``rfilter`` and ``sample_border``).
    #[pyo3(signature = (kind, stddev, sample_border))]
    fn set_filter(&mut self, kind: &str, stddev: f64, sample_border: bool) -> PyResult<()> {
        let filter = match choice("rfilter", kind, &[("box", false), ("gaussian", true)])? {
            false => Filter::Box,
            true => Filter::gaussian(stddev)?,
        };
        self.filter = Some((filter, sample_border));
        Ok(())
    }

    /// The scene, with its BVH and light selection built.
    fn build(&mut self, py: Python<'_>) -> PyResult<PyScene> {
        let (camera, width, height) = self.camera.ok_or_else(|| Error::Argument {
            arg: "sensor",
            message: "the scene has no sensor".into(),
        })?;
        let shapes = std::mem::take(&mut self.shapes);
        let environment = self.environment.take();
        let (filter, sample_border) = self.filter.unwrap_or((Filter::Box, false));
        let scene = py.detach(|| {
            guarded(|| {
                Ok(Scene::new(shapes, environment, camera, width, height)?
                    .with_filter(filter, sample_border)?)
            })
        })?;
        Ok(PyScene(Arc::new(scene)))
    }
}

/// A scene ready to render (``mcsample.Scene`` holds one).
#[pyclass(module = "mcsample._core.render", name = "CompiledScene", frozen)]
pub struct PyScene(Arc<Scene>);

#[pymethods]
impl PyScene {
    /// ``(width, height)`` of the film in pixels.
    #[getter]
    fn film(&self) -> (usize, usize) {
        self.0.film()
    }

    /// What traces the scene's triangle meshes: ``"embree 3.13.5"``
    /// (Intel Embree 3, loaded at run time) or ``"obvhs"``.
    #[getter]
    fn ray_tracer(&self) -> String {
        self.0.ray_tracer()
    }

    /// The camera seen from points ``x`` (N, 3) or (3,), as light tracing
    /// connects to it (Mitsuba's ``sensor.sample_direction``), with
    /// uniform ``u`` (N, 2) or (2,) placing the point on a thin lens's
    /// aperture. Returns float64 (N, 8) or (8,): the film position in
    /// pixels (2; x right, y down), the unit direction from ``x`` to the
    /// lens point (3), the distance, the density per steradian of that
    /// point (1 for a pinhole) and the importance weight; all 0 where
    /// ``x`` is outside the clip range or the ray misses the film.
    fn sample_sensor<'py>(
        &self,
        py: Python<'py>,
        x: &Obj<'py>,
        u: &Obj<'py>,
    ) -> PyResult<Obj<'py>> {
        let (width, height) = self.0.film();
        self.at_points(py, x, (u, "u", Check::Unit), |scene, x, u| {
            let s = scene.camera().sample_direction(x, u, 0.0);
            s.map_or([0.0; 8], |s| {
                let [dx, dy, dz] = s.d.to_array().map(f64::from);
                [
                    f64::from(s.film[0]) * width as f64,
                    f64::from(s.film[1]) * height as f64,
                    dx,
                    dy,
                    dz,
                    f64::from(s.dist),
                    f64::from(s.pdf),
                    f64::from(s.weight),
                ]
            })
        })
    }

    /// Emitter sampling, as the renderer's next-event estimation does it
    /// under emitter sampling alone (under MIS a map is drawn by its
    /// compensated density instead):
    /// from points ``x`` (N, 3) or (3,), with uniform numbers ``u`` (N, 3)
    /// or (3,) in [0, 1] (the light's choice, then two for the point or
    /// direction on it). Returns float64 (N, 8) or (8,): the unit
    /// direction (3), its density per steradian (the light's choice
    /// included), the radiance arriving along it (3, no visibility test)
    /// and the distance to the light point (inf for the environment);
    /// all 0 where the sample carries no light (the back of a light).
    fn sample_emitter<'py>(
        &self,
        py: Python<'py>,
        x: &Obj<'py>,
        u: &Obj<'py>,
    ) -> PyResult<Obj<'py>> {
        self.at_points(py, x, (u, "u", Check::Unit), |scene, x, u| {
            let s = scene.sample_light(x, u, None::<fn() -> u64>);
            s.map_or([0.0; 8], |s| {
                let [dx, dy, dz] = s.d.to_array();
                let [r, g, b] = s.radiance;
                [dx, dy, dz, s.pdf, r, g, b, s.dist].map(f64::from)
            })
        })
    }

    /// The density per steradian with which :meth:`sample_emitter` from
    /// points ``x`` (N, 3) or (3,) draws the unit directions ``d`` (N, 3)
    /// or (3,): float64 (N,) or a scalar.
    fn emitter_pdf<'py>(&self, py: Python<'py>, x: &Obj<'py>, d: &Obj<'py>) -> PyResult<Obj<'py>> {
        self.at_points(py, x, (d, "d", Check::Finite), |scene, x, d| {
            let d = Vec3A::from(d).normalize_or_zero();
            if d == Vec3A::ZERO {
                return [0.0];
            }
            [f64::from(scene.emitter_pdf(x, d))]
        })
    }
}

impl PyScene {
    /// `kernel(scene, x, v)` for each world point `x` of `x` (N, 3) or (3,)
    /// and its row of `v` (N, K) or (K,) (argument `arg`, checked by
    /// `check`), in `f32`, as float64 rows of `M`; the GIL released.
    fn at_points<'py, const K: usize, const M: usize>(
        &self,
        py: Python<'py>,
        x: &Obj<'py>,
        (v, arg, check): (&Obj<'py>, &'static str, Check),
        kernel: impl Fn(&Scene, Vec3A, [f32; K]) -> [f64; M] + Sync + Send,
    ) -> PyResult<Obj<'py>> {
        let x = Points::<f64, 3>::extract(x, "x")?;
        let v = Points::<f64, K>::extract(v, arg)?;
        let scene = &self.0;
        map_pair(py, (&x, Check::Finite), (&v, check), |x, v| {
            kernel(scene, Vec3A::from(x.map(|c| c as f32)), v.map(|c| c as f32))
        })
    }
}

/// Renders samples ``first_sample .. first_sample + spp`` of each pixel's
/// sequence of ``total_spp`` (default ``first_sample + spp``) of ``scene``;
/// returns ``(image, variance, luminance_variance, blocks, sums)``: flat
/// float32 arrays of ``height * width * 3`` (the third ``height * width``),
/// the samples' blocks as ``(start, length)`` pairs, and (when
/// ``keep_sums``) their float64 sums, 8 per pixel and block, else None.
/// With ``strategies`` (``integrator="bdpt"``), the three arrays hold
/// after the render's pixels, per strategy of ``mcsample._core.render.
/// bdpt_strategies(max_depth)``, its weighted then unweighted image.
/// ``callback(samples_done)`` is
/// called about ten times a second, holding the GIL; a pending signal (such
/// as Ctrl-C) stops the render and is raised once its threads have stopped.
#[pyfunction]
#[pyo3(signature = (scene, spp, seed, integrator, strategy, heuristic, max_depth, rr_depth, hide_emitters = false, callback = None, sampler = "independent", first_sample = None, total_spp = None, keep_sums = false, strategies = false))]
#[allow(clippy::too_many_arguments)]
pub fn render<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyScene>,
    spp: &Obj<'py>,
    seed: &Obj<'py>,
    integrator: &str,
    strategy: &str,
    heuristic: &str,
    max_depth: &Obj<'py>,
    rr_depth: &Obj<'py>,
    hide_emitters: bool,
    callback: Option<Obj<'py>>,
    sampler: &str,
    first_sample: Option<Obj<'py>>,
    total_spp: Option<Obj<'py>>,
    keep_sums: bool,
    strategies: bool,
) -> PyResult<Film<'py>> {
    let spp = index_arg(spp, "spp", 1, u64::from(u32::MAX))? as u32;
    let first = match first_sample {
        Some(k) => index_arg(&k, "first_sample", 0, MAX_TOTAL - u64::from(spp))?,
        None => 0,
    };
    let total = match total_spp {
        Some(t) => index_arg(&t, "total_spp", first + u64::from(spp), MAX_TOTAL)?,
        None => first + u64::from(spp),
    };
    let samples = Samples {
        first,
        count: spp,
        total,
        keep_sums,
    };
    let seed = seed_arg(seed, "seed")?;
    let rr_depth = index_arg(rr_depth, "rr_depth", 0, u64::from(u32::MAX))? as u32;
    let settings = Settings {
        integrator: choice(
            "integrator",
            integrator,
            &[
                ("direct", Integrator::Direct),
                ("path", Integrator::Path),
                ("ptracer", Integrator::Ptracer),
                ("bdpt", Integrator::Bdpt),
            ],
        )?,
        strategy: choice(
            "strategy",
            strategy,
            &[
                ("bsdf", Strategy::Bsdf),
                ("emitter", Strategy::Emitter),
                ("mis", Strategy::Mis),
            ],
        )?,
        heuristic: heuristic_arg(heuristic)?,
        max_depth: depth_arg(max_depth, "max_depth")?,
        rr_depth,
        hide_emitters,
        sampler: choice("sampler", sampler, Sampler::NAMES)?,
        strategies,
    };
    let bounded = settings.max_depth.is_some_and(|d| (1..=64).contains(&d));
    let refuse = |message: &str| {
        Err(Error::Argument {
            arg: "strategies",
            message: message.into(),
        })
    };
    if strategies && (settings.integrator != Integrator::Bdpt || !bounded) {
        return refuse(
            "strategies=True needs integrator='bdpt' and a max_depth in [1, 64] (its images \
             are one per strategy of each path length)",
        )?;
    }
    if strategies && keep_sums {
        return refuse(
            "strategies=True renders whole images: it does not combine with first_sample",
        )?;
    }
    let scene = Arc::clone(&scene.get().0);
    let progress = Arc::new(Progress::default());
    let (tx, rx) = mpsc::channel();
    let worker = {
        let progress = Arc::clone(&progress);
        std::thread::spawn(move || {
            let result = guarded(|| {
                Ok(crate::render::render(
                    &scene, samples, seed, &settings, &progress,
                )?)
            });
            // The receiver outlives this thread (it joins it).
            let _ = tx.send(result);
        })
    };
    let tick = Duration::from_millis(100);
    let mut rx = rx;
    let outcome = loop {
        // The receiver is Send but not Sync: it goes into the GIL-free
        // closure and comes back out.
        let (received, back) = py.detach(move || (rx.recv_timeout(tick), rx));
        rx = back;
        match received {
            Ok(result) => break result,
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                break Err(pyo3::exceptions::PyRuntimeError::new_err(
                    "internal error in mcsample: the render thread stopped without a result",
                ));
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {}
        }
        let interrupted = py.check_signals().and_then(|()| match &callback {
            Some(cb) => cb
                .call1((progress.samples.load(std::sync::atomic::Ordering::Relaxed),))
                .map(|_| ()),
            None => Ok(()),
        });
        if let Err(e) = interrupted {
            progress
                .cancel
                .store(true, std::sync::atomic::Ordering::Relaxed);
            py.detach(move || {
                let _ = rx.recv();
            });
            let _ = worker.join();
            return Err(e);
        }
    };
    let _ = worker.join();
    let image = outcome?;
    Ok(film(
        py,
        [image.mean, image.variance, image.luminance_variance],
        &image.blocks,
        keep_sums.then_some(image.sums),
    ))
}

/// The longest sequence of samples a pixel may have (2^63).
const MAX_TOTAL: u64 = 1 << 63;

/// What [`render`] and [`merge`] return: image, variance, luminance
/// variance, blocks, sums.
type Film<'py> = (
    Bound<'py, PyArray1<f32>>,
    Bound<'py, PyArray1<f32>>,
    Bound<'py, PyArray1<f32>>,
    Vec<(u64, u64)>,
    Option<Bound<'py, PyArray1<f64>>>,
);

fn film<'py>(
    py: Python<'py>,
    [mean, variance, luminance_variance]: [Vec<f32>; 3],
    blocks: &[Block],
    sums: Option<Vec<f64>>,
) -> Film<'py> {
    (
        PyArray1::from_vec(py, mean),
        PyArray1::from_vec(py, variance),
        PyArray1::from_vec(py, luminance_variance),
        blocks.iter().map(|b| (b.start, b.len)).collect(),
        sums.map(|s| PyArray1::from_vec(py, s)),
    )
}

/// A chunk of a render: its blocks as `(start, length)` and its sums.
type Chunk<'py> = (Vec<(u64, u64)>, PyReadonlyArray1<'py, f64>);

/// Merges chunks of one render: ``chunks`` is a list of ``(blocks, sums)``
/// as :func:`render` returns them with ``keep_sums``, in sample order, for a
/// film of ``pixels`` pixels; returns what :func:`render` returns for the
/// samples they cover (the same bits as rendering those samples at once).
/// ``paths_per_sample`` is 1, or ``pixels`` for light tracing (whose
/// sample index holds one light path per pixel).
#[pyfunction]
#[pyo3(signature = (chunks, pixels, paths_per_sample = None))]
pub fn merge<'py>(
    py: Python<'py>,
    chunks: Vec<Chunk<'py>>,
    pixels: usize,
    paths_per_sample: Option<Obj<'py>>,
) -> PyResult<Film<'py>> {
    let per_sample = match paths_per_sample {
        Some(n) => index_arg(&n, "paths_per_sample", 1, u64::from(u32::MAX))?,
        None => 1,
    };
    let mut parts = Vec::with_capacity(chunks.len());
    for (blocks, sums) in &chunks {
        let blocks = blocks
            .iter()
            .map(|&(start, len)| Block::checked(start, len))
            .collect::<Result<Vec<_>, _>>()?;
        parts.push((blocks, sums.as_slice()?));
    }
    let merged = py.detach(|| film::merge(&parts, pixels, per_sample))?;
    Ok(film(
        py,
        [merged.mean, merged.variance, merged.luminance_variance],
        &merged.blocks,
        Some(merged.sums),
    ))
}

/// The strategies ``(s, t)`` of bidirectional path tracing's paths of at
/// most ``max_depth`` segments (at most 64), in the order of
/// :func:`render`'s strategy images: by path length, then by ``s`` (light
/// vertices); ``(1, 1)`` is not used.
#[pyfunction]
pub fn bdpt_strategies(max_depth: &Obj<'_>) -> PyResult<Vec<(u32, u32)>> {
    let max_depth = index_arg(max_depth, "max_depth", 1, 64)? as u32;
    Ok(crate::render::bdpt::strategies(max_depth))
}

/// Registers ``mcsample._core.render``.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PySceneBuilder>()?;
    m.add_class::<PyScene>()?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(merge, m)?)?;
    m.add_function(wrap_pyfunction!(bdpt_strategies, m)?)?;
    Ok(())
}
