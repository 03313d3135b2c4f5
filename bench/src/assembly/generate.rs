//! The car-like assembly of B8, generated from a seed and written as binary STL files and one
//! scene config: a body of large panels (a ribbed floor pan, a crowned roof and two side panels,
//! all open sheets; a firewall and a rear panel, closed slabs), small fittings (brackets, bolts,
//! blocks, cylinders, pipes) strewn through the cabin, and the movable bar the hand grasps.
//!
//! Of the triangles, the bar has 2 %, the panels 78 % (the floor pan 20 %, the roof 16 %, each
//! side 12 %, the firewall 10 %, the rear panel 8 %) and the fittings 20 %, shared evenly: with
//! the default 1,000 parts and 5M triangles, panels of 400k to 1M triangles, a 100k-triangle bar
//! and fittings of about 1,000. The procedural shapes meet their counts only about, so the floor
//! pan takes what is left: the assembly has exactly the triangles asked for.
//!
//! The bar comes first and the panels next. The fittings are kept out of the region the bar and
//! the hand sweep on the scripted path, so that the bar meets the right side panel and nothing
//! else.

use std::f64::consts::TAU;
use std::fs::File;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use vas_protocol::WirePose;
use vas_server::geometry::{TriMesh, shapes};

use super::meshes::{Fitting, open_sheet, random_rotation};
use super::path::{BAR_LENGTH, BAR_RADIUS, PANEL_Y, ScriptedPath, bar_pose};

/// The bar's part id: it comes first in the scene.
pub const BAR_ID: u32 = 0;

/// The bar's share of the triangles.
const BAR_SHARE: f64 = 0.02;
/// The fittings' share of the triangles, split evenly among them.
const FITTINGS_SHARE: f64 = 0.2;
/// The fewest triangles a fitting may have.
const MIN_FITTING_TRIANGLES: usize = 100;

/// The cabin's extent, metres (x forward, y left, z up; the floor pan at z = 0).
const CABIN_X: [f64; 2] = [-2.0, 1.2];
const CABIN_Y: [f64; 2] = [PANEL_Y, -PANEL_Y];
const CABIN_HEIGHT: f64 = 1.25;
/// The ribs of the floor pan: height and pitch along x (metres).
const RIB_HEIGHT: f64 = 0.006;
const RIB_PITCH: f64 = 0.2;
/// How much the roof rises in its middle, and the left side leans in at its top (metres).
const ROOF_CROWN: f64 = 0.05;
const SIDE_TUMBLEHOME: f64 = 0.06;
/// The thickness of the firewall and the rear panel.
const SLAB: f64 = 0.03;

/// The panels of the body other than the floor pan: name, share of the triangles, and the
/// mesh with its pose for a count.
type PanelBuilder = fn(usize) -> (TriMesh, Isometry3<f64>);
const PANELS: [(&str, f64, PanelBuilder); 5] = [
    ("roof", 0.16, roof),
    ("side_right", 0.12, side_right),
    ("side_left", 0.12, side_left),
    ("firewall", 0.10, |n| slab(n, CABIN_X[1] + SLAB / 2.0)),
    ("rear_panel", 0.08, |n| slab(n, CABIN_X[0] - SLAB / 2.0)),
];

/// What to generate.
#[derive(Debug, Clone, Copy)]
pub struct AssemblySpec {
    /// Parts in all: the bar, six panels and the fittings.
    pub parts: usize,
    /// Triangles in all.
    pub triangles: usize,
    /// The seed of the fittings' kinds, sizes and places.
    pub seed: u64,
}

impl AssemblySpec {
    /// The bar and the panels.
    pub const FIXED_PARTS: usize = 1 + 1 + PANELS.len();

    fn fittings(&self) -> usize {
        self.parts - Self::FIXED_PARTS
    }
}

/// The written assembly.
#[derive(Debug, Clone)]
pub struct Assembly {
    /// The scene config.
    pub scene: PathBuf,
    /// Parts and triangles in all.
    pub parts: usize,
    pub triangles: usize,
    /// The bar's triangles and mesh file.
    pub bar_triangles: usize,
    pub bar_file: PathBuf,
    /// The static parts whose boxes come near the bar's path: mesh file and pose.
    pub near_path: Vec<(PathBuf, Isometry3<f64>)>,
}

/// A part as the scene config lists it.
#[derive(Debug, Serialize)]
struct PartEntry {
    name: String,
    mesh: String,
    position: [f64; 3],
    rotation: [f64; 4],
    movable: bool,
}

/// The scene config.
#[derive(Debug, Serialize)]
struct SceneFile<'a> {
    name: &'a str,
    hand: &'a Path,
    parts: Vec<PartEntry>,
}

/// A part generated and written, with what the oracle needs to know of it.
struct Written {
    entry: PartEntry,
    file: PathBuf,
    pose: Isometry3<f64>,
    triangles: usize,
    /// The part's box in the world.
    world_box: (Point3<f64>, Point3<f64>),
}

/// Generates the assembly of `spec` around `path` into `dir` (as `assembly.toml` and one STL
/// file a part) with the hand model `hand`.
pub fn generate(
    dir: &Path,
    spec: &AssemblySpec,
    hand: &Path,
    path: &ScriptedPath,
) -> Result<Assembly> {
    if spec.parts < AssemblySpec::FIXED_PARTS {
        bail!(
            "the assembly needs at least {} parts: the bar and six panels",
            AssemblySpec::FIXED_PARTS
        );
    }
    let share = |fraction: f64| (spec.triangles as f64 * fraction).round() as usize;
    let per_fitting = share(FITTINGS_SHARE)
        .checked_div(spec.fittings())
        .unwrap_or(0);
    if spec.fittings() > 0 && per_fitting < MIN_FITTING_TRIANGLES {
        bail!(
            "{} triangles leave {per_fitting} for each of {} fittings; they need {MIN_FITTING_TRIANGLES}",
            spec.triangles,
            spec.fittings()
        );
    }
    let hand =
        std::path::absolute(hand).with_context(|| format!("the hand model {}", hand.display()))?;
    let write = |name: String, mesh: TriMesh, pose: Isometry3<f64>, movable: bool| {
        write_part(dir, name, &mesh, pose, movable)
    };

    let mut parts = vec![write(
        "bar".into(),
        shapes::cylinder(BAR_RADIUS, BAR_LENGTH, share(BAR_SHARE).max(100)),
        bar_pose(),
        true,
    )?];
    for (name, fraction, build) in PANELS {
        let (mesh, pose) = build(share(fraction));
        parts.push(write(name.into(), mesh, pose, false)?);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let keep_out = path.keep_out();
    for index in 0..spec.fittings() {
        let fitting = Fitting::ALL[index % Fitting::ALL.len()];
        let mesh = fitting.mesh(per_fitting, &mut rng);
        let pose = place_outside(&mesh, keep_out, &mut rng);
        let name = format!("{}_{index:04}", fitting.name());
        parts.push(write(name, mesh, pose, false)?);
    }
    let taken: usize = parts.iter().map(|part| part.triangles).sum();
    let Some(floor) = spec.triangles.checked_sub(taken).filter(|&n| n >= 2) else {
        bail!(
            "{} triangles are too few: the other parts took {taken}",
            spec.triangles
        );
    };
    parts.insert(
        1,
        write(
            "floor_pan".into(),
            floor_pan(floor),
            Isometry3::identity(),
            false,
        )?,
    );

    let region = path.bar_region(NEAR_PATH_MARGIN);
    let near_path = (parts.iter().skip(1))
        .filter(|part| boxes_overlap(part.world_box, region))
        .map(|part| (part.file.clone(), part.pose))
        .collect();
    let assembly = Assembly {
        scene: dir.join("assembly.toml"),
        parts: parts.len(),
        triangles: parts.iter().map(|part| part.triangles).sum(),
        bar_triangles: parts[0].triangles,
        bar_file: parts[0].file.clone(),
        near_path,
    };
    let scene = SceneFile {
        name: "assembly",
        hand: &hand,
        parts: parts.into_iter().map(|part| part.entry).collect(),
    };
    let text = toml::to_string(&scene).context("the scene config")?;
    std::fs::write(&assembly.scene, text)
        .with_context(|| format!("writing {}", assembly.scene.display()))?;
    Ok(assembly)
}

/// How far from the bar's swept box a static part counts as near the path (metres).
const NEAR_PATH_MARGIN: f64 = 0.05;

/// Writes `mesh` as `<name>.stl` in `dir` and returns the part.
fn write_part(
    dir: &Path,
    name: String,
    mesh: &TriMesh,
    pose: Isometry3<f64>,
    movable: bool,
) -> Result<Written> {
    let file = dir.join(format!("{name}.stl"));
    write_stl(&file, mesh).with_context(|| format!("writing {}", file.display()))?;
    let (lo, hi) = mesh.vertices().iter().map(|v| pose * v).fold(
        (Point3::from([f64::MAX; 3]), Point3::from([f64::MIN; 3])),
        |(lo, hi), p| (lo.inf(&p), hi.sup(&p)),
    );
    let wire = WirePose::from_isometry(&pose);
    Ok(Written {
        entry: PartEntry {
            mesh: format!("{name}.stl"),
            name,
            position: wire.position,
            rotation: wire.rotation,
            movable,
        },
        file,
        pose,
        triangles: mesh.triangles().len(),
        world_box: (lo, hi),
    })
}

/// Writes `mesh` as binary STL (single-precision coordinates, as the format holds them).
fn write_stl(path: &Path, mesh: &TriMesh) -> std::io::Result<()> {
    let corner = |p: &Point3<f64>| stl_io::Vertex::new(p.coords.cast::<f32>().into());
    let triangles = (0..mesh.triangles().len()).map(|t| {
        let [a, b, c] = mesh.triangle(t);
        let normal = (b - a).cross(&(c - a)).normalize().cast::<f32>();
        stl_io::Triangle {
            normal: stl_io::Normal::new(normal.into()),
            vertices: [corner(&a), corner(&b), corner(&c)],
        }
    });
    stl_io::write_stl(&mut File::create(path)?, triangles)
}

/// A pose for a fitting in the cabin, turned at random, whose bounding sphere stays out of
/// `keep_out`.
fn place_outside(
    mesh: &TriMesh,
    keep_out: (Point3<f64>, Point3<f64>),
    rng: &mut ChaCha8Rng,
) -> Isometry3<f64> {
    let (centre, radius) = mesh.bounding_sphere();
    let (lo, hi) = (
        keep_out.0 - Vector3::repeat(radius),
        keep_out.1 + Vector3::repeat(radius),
    );
    loop {
        let rotation = random_rotation(rng);
        let at = Point3::new(
            rng.random_range(CABIN_X[0] + 0.1..CABIN_X[1] - 0.1),
            rng.random_range(CABIN_Y[0] + 0.1..CABIN_Y[1] - 0.1),
            rng.random_range(0.05..CABIN_HEIGHT - 0.1),
        );
        let middle = at + rotation * centre.coords;
        let inside = (0..3).all(|axis| lo[axis] < middle[axis] && middle[axis] < hi[axis]);
        if !inside {
            return Isometry3::from_parts(Translation3::from(at.coords), rotation);
        }
    }
}

/// Whether two boxes overlap.
fn boxes_overlap(a: (Point3<f64>, Point3<f64>), b: (Point3<f64>, Point3<f64>)) -> bool {
    (0..3).all(|axis| a.0[axis] <= b.1[axis] && b.0[axis] <= a.1[axis])
}

/// The floor pan: an open sheet over the cabin's floor with ribs across it.
fn floor_pan(triangles: usize) -> TriMesh {
    let (length, width) = (CABIN_X[1] - CABIN_X[0], CABIN_Y[1] - CABIN_Y[0]);
    open_sheet(triangles, length / width, |u, v| {
        let x = CABIN_X[0] + length * u;
        Point3::new(
            x,
            CABIN_Y[0] + width * v,
            RIB_HEIGHT * (TAU * x / RIB_PITCH).sin(),
        )
    })
}

/// The roof: an open sheet, crowned across, a little shorter than the floor.
fn roof(triangles: usize) -> (TriMesh, Isometry3<f64>) {
    let (x0, length) = (CABIN_X[0] + 0.3, CABIN_X[1] - CABIN_X[0] - 0.8);
    let width = CABIN_Y[1] - CABIN_Y[0] - 0.1;
    let mesh = open_sheet(triangles, length / width, |u, v| {
        let across = 2.0 * v - 1.0;
        Point3::new(
            x0 + length * u,
            width / 2.0 * across,
            CABIN_HEIGHT + ROOF_CROWN * (1.0 - across * across),
        )
    });
    (mesh, Isometry3::identity())
}

/// The right side panel: a flat open sheet in the plane y = [`PANEL_Y`], which the bar slides on.
fn side_right(triangles: usize) -> (TriMesh, Isometry3<f64>) {
    let length = CABIN_X[1] - CABIN_X[0];
    let mesh = open_sheet(triangles, length / CABIN_HEIGHT, |u, v| {
        Point3::new(CABIN_X[0] + length * u, PANEL_Y, CABIN_HEIGHT * v)
    });
    (mesh, Isometry3::identity())
}

/// The left side panel: an open sheet leaning in towards its top.
fn side_left(triangles: usize) -> (TriMesh, Isometry3<f64>) {
    let length = CABIN_X[1] - CABIN_X[0];
    let mesh = open_sheet(triangles, length / CABIN_HEIGHT, |u, v| {
        Point3::new(
            CABIN_X[0] + length * u,
            CABIN_Y[1] - SIDE_TUMBLEHOME * v * v,
            CABIN_HEIGHT * v,
        )
    });
    (mesh, Isometry3::identity())
}

/// A closed slab across the cabin at `x`: the firewall or the rear panel.
fn slab(triangles: usize, x: f64) -> (TriMesh, Isometry3<f64>) {
    let size = Vector3::new(SLAB, CABIN_Y[1] - CABIN_Y[0], CABIN_HEIGHT);
    let pose = Isometry3::translation(x, 0.0, CABIN_HEIGHT / 2.0);
    (shapes::cuboid(size, triangles), pose)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn generated(spec: AssemblySpec) -> (tempfile::TempDir, Assembly) {
        let dir = tempfile::tempdir().expect("a scratch folder");
        let hand = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs/hands/right.toml");
        let assembly = generate(dir.path(), &spec, &hand, &ScriptedPath::new(1.0))
            .expect("the assembly is written");
        (dir, assembly)
    }

    #[test]
    fn the_scene_loads_with_exactly_the_parts_and_triangles_asked_for() {
        let spec = AssemblySpec {
            parts: 30,
            triangles: 60_000,
            seed: 5,
        };
        let (_dir, assembly) = generated(spec);
        assert_eq!((assembly.parts, assembly.triangles), (30, 60_000));
        let scene = vas_server::scene::Scene::load(&assembly.scene).expect("the scene loads");
        assert_eq!(scene.parts.len(), 30);
        assert_eq!(scene.triangle_count(), 60_000);
        assert!(scene.parts[BAR_ID as usize].movable);
        assert_eq!(scene.parts.iter().filter(|part| part.movable).count(), 1);
        // The right side panel, and no fitting, is near the bar's path.
        let near: Vec<_> = (assembly.near_path.iter())
            .filter_map(|(file, _)| file.file_stem()?.to_str())
            .collect();
        assert_eq!(near, ["side_right"]);
    }

    #[test]
    fn the_same_seed_gives_the_same_assembly() {
        let spec = AssemblySpec {
            parts: 12,
            triangles: 20_000,
            seed: 9,
        };
        let read = |assembly: &Assembly| std::fs::read_to_string(&assembly.scene).expect("read");
        let (_a, first) = generated(spec);
        let (_b, second) = generated(spec);
        let (_c, other) = generated(AssemblySpec { seed: 10, ..spec });
        assert_eq!(read(&first), read(&second));
        assert_ne!(read(&first), read(&other));
    }

    #[test]
    fn too_few_triangles_or_parts_are_refused() {
        let dir = tempfile::tempdir().expect("a scratch folder");
        let path = ScriptedPath::new(1.0);
        let hand = Path::new("right.toml");
        for (parts, triangles) in [(6, 100_000), (1000, 100_000)] {
            let spec = AssemblySpec {
                parts,
                triangles,
                seed: 1,
            };
            assert!(generate(dir.path(), &spec, hand, &path).is_err());
        }
    }
}
