//! `vas-bench`: the benchmarks of BENCHMARKS.md. B1-B6 run the simulation library in this
//! process; B7 (`e2e`) and the soak talk to a running `vas-server` over iceoryx2, B9
//! (`browser`) to a server and a `vas-viewer` through headless Chromium, and B0's start-up and
//! B8 (`assembly`) start servers of their own. Every benchmark prints its table and, when asked, writes `--json FILE` and draws `--svg FILE`.

mod args;
mod assembly;
mod baselines;
mod bounce;
mod browser;
mod c_library;
mod distance;
mod e2e;
mod echo;
mod filter;
mod grasp;
mod oracle;
mod orbit;
mod process;
mod random;
mod report;
mod slide;
mod slope;
mod soak;
mod startup;
mod synthetic;
mod tree_build;
mod tumble;

use std::io::IsTerminal;
use std::process::ExitCode;

use clap::{Command, CommandFactory, FromArgMatches, Parser, Subcommand};
use tracing_subscriber::EnvFilter;

/// vas benchmarks: procedures, peers and current figures are in BENCHMARKS.md.
#[derive(Debug, Parser)]
#[command(name = "vas-bench", version, about)]
struct Cli {
    #[command(subcommand)]
    benchmark: Benchmark,
}

#[derive(Debug, Subcommand)]
enum Benchmark {
    /// B0: start-up of one movable part of 1k to 2M triangles, stage by stage.
    #[command(
        after_long_help = "Columns: triangles (of the part); shape_s (generating and welding it); adjacency_s (its edge
adjacency, for sliding); hull_s (its convex hull, for the separating-plane pre-check); tree_s
(its DOP-tree); ready_s (from starting vas-server in lockstep on a scene of a floor and the
part to its answer to one tracker sample). Then the log-log slope of each column over the
rows of at least 100k triangles (1 is linear)."
    )]
    Startup(startup::StartupArgs),
    /// B0's tree build: the DOP-tree's against FCL's OBB-tree's on the same meshes.
    #[command(
        after_long_help = "Columns: mesh; triangles; dop_1_thread_s, dop_all_threads_s (median DOP-tree build, k = 18, on
one thread and on all); dop_bytes_per_tri (all the tree holds: nodes, boxes, offsets, triangles
and their ids); fcl_obb_s, fcl_bytes_per_tri (median FCL BVHModel<OBB> build on one thread, and
its memUsage: nodes, indices, vertices, triangles); ratio_1_thread and ratio (dop_1_thread_s and
dop_all_threads_s over fcl_obb_s; '(ref)' when FCL was not found at build time and the ratios are
against 2.5 s)."
    )]
    TreeBuild(tree_build::TreeBuildArgs),
    /// B1: the tumbling pair (the paper's Figure 3 with --figure).
    #[command(
        after_long_help = "Columns: algo (algorithm); d (distance of B from A); mean_us, median_us, max_us (time per
query, each query timed as its fastest of --rounds passes); pass_us (mean of one more pass timed
as a whole: the figure to read below about 50 ns); hit (fraction of poses in collision);
bv_tests, realign, tri_tests (mean bounding-volume tests, re-alignments and triangle tests per
query); doptree_x (mean_us over the DOP-tree's at the same d). Then per algorithm: build_ms
(tree build) and bytes_per_triangle (all the tree holds). mismatches: poses at which an
algorithm's answer differs from the first's (must be 0). With --figure: object, triangles,
algo, mean_us, mismatches per object of the sweep."
    )]
    Tumble(tumble::TumbleArgs),
    /// B2: random poses of one mesh against another (FCL's procedure).
    #[command(
        after_long_help = "Columns: algo; mean_us, pass_us, median_us, max_us (time per query, as in `tumble`); hit
(fraction of poses in collision); bv_tests, realign, tri_tests (mean counts per query);
doptree_x (mean_us over the DOP-tree's). Then build_ms and bytes_per_triangle per algorithm,
and the mismatches between the algorithms' answers (must be 0)."
    )]
    Random(random::RandomArgs),
    /// B3: orbiting spheres, separating plane against GJK (the paper's Figure 4).
    #[command(
        after_long_help = "Columns: algo (plane_cold, plane_cached: the separating-plane pre-check without and with the
plane of the last query; gjk_cold, gjk_warm: parry's GJK; bbox: a bounding-box test); polygons
(triangles of each sphere); distance (of the centres; touching at 2); rot_deg (spin per step);
mean_us (time per query); wrong (wrong 'not separated' answers), clear (of those, where the
spheres are more than 0.1% of the touching distance apart); wrong_sep (wrong 'separated'
answers: must be 0); apart (steps at which the spheres are apart); loops (mean hill-climbing
loops per query of the plane search)."
    )]
    Orbit(orbit::OrbitArgs),
    /// B4: objects bouncing in a cube, the whole pipeline against threads (the paper's Figure 5).
    #[command(
        after_long_help = "Columns: threads (of the pipeline's pool); objects; mean_frame_us, p99_frame_us (wall time of
a whole frame); speedup (the first row's mean frame over this row's); box_pairs (pairs whose
boxes overlap), unseparated (pairs the separating plane left for the exact test), colliding,
split (exact tests split across threads), per frame; broad_us, plane_us, exact_us (mean time
per frame of the broad phase, the separating-plane stage and the exact tests)."
    )]
    Bounce(bounce::BounceArgs),
    /// B5: sliding contact, time per contact point and sliding frame rate.
    #[command(
        after_long_help = "Columns: scene; threads (collision queries may split across them); triangles (of the grasped
part); contact_points (handled in one run); us_per_contact_excl_cd, us_per_contact_incl_cd
(median time per contact point, without and with collision detection); steps_per_s (sliding
frames per second, collision detection included); penetrations (visible poses parry found
penetrating: must be 0)."
    )]
    Slide(slide::SlideBenchArgs),
    /// B6: time per clasp minimisation of the hand against parts of 1k to 50k triangles.
    #[command(
        after_long_help = "Columns: part; triangles; mean, p99 and max clasp us (time per clasp minimisation, median over
--repeats); mean and p99 frame us (the whole grasping frame: clasp, contacts, analysis); steps
(clasp iterations per frame); checks (segment collision checks per frame); grasp (the type
the analysis recognised; a warning follows when it is not the expected one)."
    )]
    Grasp(grasp::GraspArgs),
    /// B7: input-to-answer latency through a running server beside the raw iceoryx2 round trip.
    #[command(
        after_long_help = "Columns: path (raw: the bare iceoryx2 round trip through an echo process; c, with
--c-library: the same through the C library's calls; vas: through the server); p50_us, p99_us,
max_us (from publishing a sample to receiving the hand frame that answers it); samples
(measured exchanges); unanswered (no answer within the timeout)."
    )]
    E2e(e2e::E2eArgs),
    /// B8: a car-like assembly of 1,000 parts and 5M triangles: start-up cold and cached,
    /// memory, and a grasped bar slid along a panel at 1 kHz.
    #[command(
        after_long_help = "Generates the assembly (seeded) as STL files and a scene, then starts vas-server on it twice,
each with --tree-cache. Figures: ready_s_cold (from starting the server to its answer to the
first sample, the tree cache empty: every tree built and stored); ready_s_cached (the same with
the cache the cold run filled); tree_cache_files (trees stored); peak_rss_mb (the server's
VmHWM, the larger of the two runs, MiB); bytes_per_triangle (peak RSS) (that peak over the
triangles: everything the server holds, not the trees alone). In the cached run, after a reset,
the hand is driven at 1 kHz: it grasps the bar, presses its end onto the right side panel and
slides it along: drive_s (its time); samples, unanswered (tracker samples sent, and those not
answered within --answer-timeout-ms); grasped (a parts frame showed the bar grasped);
sliding_frames (parts frames that showed it sliding along a contact); slid_m (how far it moved
while sliding); checked_poses, penetrations (the bar's published poses, and those parry finds
penetrating a static part near the path: must be 0); e2e_p50_us, e2e_p99_us, e2e_max_us (from
publishing a tracker sample to the hand frame answering it, as in `e2e`). Per loop, from the
server's log over the drive: hz (frames over the drive's time); p99_us, max_us (frame time:
the largest window's 99th percentile, and the longest)."
    )]
    Assembly(assembly::AssemblyArgs),
    /// Feeds a running server at a steady rate for a long time; reports dropped samples and
    /// the server's memory.
    #[command(
        after_long_help = "Output: per stream the samples sent, answered, superseded (merged into the frame of a newer
sample of the stream) and dropped; the latency from a sample to its first answer; how late the
pacing sent samples; the server's resident memory at the start, the end, its maximum and its
growth in KiB per minute."
    )]
    Soak(soak::SoakArgs),
    /// B9: from the server's publish to the viewer's pages in a browser, and to the drawn frame.
    #[command(
        after_long_help = "Needs a running server and vas-viewer, and Debian's chromium and chromium-driver. Columns:
pages (windows open in one headless Chromium); frames_per_page_per_s (frames each page
received); transport_p50_ms, transport_p99_ms, transport_max_ms (from the server's publish
stamp to the page's receipt, over every page's frames); draw_p50_ms, draw_p99_ms (from the
receipt to the end of the animation frame that drew it); fps (animation frames per second per
page); superseded_% (frames replaced by a newer one before they were drawn); viewer_cpu_%
(the viewer's CPU time over the span, in percent of one core); clock_skew_ms (the page's
high-resolution wall clock minus the system's: how far transport figures can be off)."
    )]
    Browser(browser::BrowserArgs),
    /// B11: exact mesh-mesh distance, coherent and random poses, against coal and FCL.
    #[command(
        after_long_help = "Columns: pair (one mesh: two copies of it; A+B); proc (coherent: B1's tumbling poses at
distance d; random: B2's poses); method (doptree: the DOP-tree with the pair's DistanceMemory
carried from pose to pose; doptree-cold: a fresh memory at every query, random poses only; coal, fcl: the peers'
OBBRSS distance, each in its own process, listed when found at build time); touch (poses at
distance 0); mean_us, p99_us, max_us (time per query, each pose timed as its fastest of --rounds
passes); coal_x (mean_us over coal's at the same poses); max_diff (largest difference of the
distance from coal's at one pose); pt_err (largest distance of a closest point from the triangle
named, or of the two points apart from the distance answered); bv_tests, tri_tests (the
DOP-tree's mean bounding-volume tests and triangle distances per query). Then the bars, met or
missed."
    )]
    Distance(distance::DistanceArgs),
    /// B14: the One Euro filter of hand tracking on the real captures, with noise added.
    #[command(
        after_long_help = "Columns: capture; jitter_mm, filtered_mm (the palm's RMS distance from its mean position with
the hand held still, unfiltered and filtered); reduction_x (their ratio); jitter_deg,
filtered_deg, reduction_deg_x (the same for its rotation); flex_deg, filtered_flex_deg (the flex
values' RMS deviation from their means); lag_ms (how far the filtered palm trails the noise-free
one at --speed, in time, over the second half of the motion); max_lag_ms (the most over the
motion); turn_lag_ms (the same as lag_ms for its rotation, the hand turning at --turn rad/s).
Then the bars, met or missed."
    )]
    Filter(filter::FilterArgs),
    /// Answers every input sample at once with a hand frame (the raw path of `e2e`).
    #[command(hide = true)]
    Echo(args::ServerArgs),
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()))
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .init();
    let matches = comma_separated_lists(Cli::command()).get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|error| error.exit());
    let result = match cli.benchmark {
        Benchmark::Startup(args) => startup::run(&args),
        Benchmark::TreeBuild(args) => tree_build::run(&args),
        Benchmark::Tumble(args) => tumble::run_cli(&args),
        Benchmark::Random(args) => random::run_cli(&args),
        Benchmark::Orbit(args) => orbit::run_cli(&args),
        Benchmark::Bounce(args) => bounce::run_cli(&args),
        Benchmark::Slide(args) => slide::run_bench(&args).map(drop),
        Benchmark::Grasp(args) => grasp::run_cli(&args),
        Benchmark::E2e(args) => e2e::run(&args),
        Benchmark::Assembly(args) => assembly::run(&args),
        Benchmark::Soak(args) => soak::run(&args),
        Benchmark::Browser(args) => browser::run(&args),
        Benchmark::Distance(args) => distance::run_cli(&args),
        Benchmark::Filter(args) => filter::run(&args),
        Benchmark::Echo(args) => echo::run(args.prefix.as_deref()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::FAILURE
        }
    }
}

/// Shows every comma-separated list as one in `--help`: its value name ends in `,...` and its
/// default reads `1,2` (clap would join a list's default values with spaces, which the command
/// line does not take).
fn comma_separated_lists(command: Command) -> Command {
    command.mut_subcommands(|benchmark| {
        benchmark.mut_args(|arg| {
            if arg.get_value_delimiter() != Some(',') {
                return arg;
            }
            let name = arg.get_id().as_str().to_uppercase().replace('-', "_");
            let defaults: Vec<String> = arg
                .get_default_values()
                .iter()
                .map(|value| value.to_string_lossy().into_owned())
                .collect();
            let arg = arg.value_name(format!("{name},..."));
            if defaults.is_empty() {
                arg
            } else {
                arg.default_value(defaults.join(","))
            }
        })
    })
}
