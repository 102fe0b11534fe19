//! # mp-report — pictures and the HTML report of a motion-program analysis
//!
//! * `plots`: per-joint trajectory plots (each coordinate against time,
//!   keypoints as dots, the executed program coloured by primitive kind).
//! * `timeline`: primitives of every joint by kind, the counted
//!   repetitions and the abstract program's loops, over one time axis.
//! * `draw`: skeletons on frames or on a blank canvas, contact sheets.
//! * `frames`: reduced JPEG copies of video frames for the report.
//! * `page`: the report, `report.html` and the folder `report/` beside it
//!   whose frames and data the page loads as it plays (`page::cards`: the
//!   summary cards; `page::panels`: the panels' contents; `page::data`:
//!   the folder's files and their size budgets).
//! * `people`: several people on the page (the people strip).
//! * `pictures`: every picture of an analysis, written into an output
//!   folder.
//! * `raster`: SVG → PNG (resvg, pure Rust), PNG/JPEG encoding.
//! * `outdir`: an output folder whose files appear complete or not at all,
//!   cancelled through a `CancelToken`.
//!
//! Pictures are written as SVG (exact, small, readable in any browser) and
//! rasterised to PNG from the same SVG, so both always agree.
//!
//! ```
//! use mp_concrete::{Program, SynthParams};
//! use mp_geom::{perform, PerformerParams};
//! use mp_report::{timeline_svg, TimelineParams};
//!
//! // The timeline picture of the performer's program (the product's synthesis).
//! let track = perform(&PerformerParams::default())?.track_2d;
//! let program = Program::synthesize(&track, &SynthParams::default())?;
//! let (svg, axis) = timeline_svg(&program, &[], &[], &TimelineParams::default())?;
//! assert!(svg.starts_with("<svg") && axis.frames == track.n_frames());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod draw;
mod error;
mod frames;
mod outdir;
mod page;
mod people;
mod pictures;
mod plots;
mod raster;
mod style;
mod svg;
mod timeline;

pub use error::ReportError;
pub use frames::{FrameStore, FrameStoreParams};
pub use outdir::OutputDir;
pub use page::{
    standard_cards, write_report, Card, PersonPage, ProgramView, ReportInput, ReportPage,
};
pub use people::PersonRow;
pub use pictures::{write_pictures, Analysed};
pub use plots::{joint_trajectory_svg, PlotParams};
pub use timeline::{timeline_svg, TimeAxis, TimelineParams};

pub use draw::{
    contact_sheet, draw_pose, draw_skeleton, frame_tile, ContactSheetParams, SkeletonStyle, Tile,
    View,
};
pub use frames::{jpeg_size, read_jpeg};
pub use outdir::{check_cancel, emergency_cleanup, RUN_FILES};
pub use page::data::registered;
pub use page::data::{CHUNK_FRAMES, FOLDER_BUDGET_BYTES, FRAMES_BUDGET_BYTES};
pub use page::PAGE;
pub use people::found_runs;
pub use raster::encode_jpeg;
pub use raster::{pixmap_to_png, pixmap_to_rgb, rgb_to_pixmap, svg_to_pixmap};
/// The drawing surface of every picture (premultiplied RGBA).
pub use resvg::tiny_skia::Pixmap;
