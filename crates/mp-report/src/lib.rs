//! # mp-report — pictures and the HTML report of a motion-program analysis
//!
//! * [`plots`]: per-joint trajectory plots (each coordinate against time,
//!   keypoints as dots, the executed program coloured by primitive kind).
//! * [`timeline`]: primitives of every joint by kind and the detected loops
//!   with iteration boundaries and counts, over one time axis.
//! * [`draw`]: skeletons on frames or on a blank canvas, contact sheets.
//! * [`frames`]: reduced JPEG copies of video frames for the report.
//! * [`html`]: the self-contained report page.
//! * [`people`]: several people on the page (the picker and the people strip).
//! * [`pictures`]: every picture of an analysis and its report page, written
//!   into an output folder.
//! * [`raster`]: SVG → PNG (resvg, pure Rust), PNG/JPEG encoding.
//! * [`outdir`]: an output folder whose files appear complete or not at all,
//!   cancelled through a `CancelToken`.
//!
//! Pictures are written as SVG (exact, small, readable in any browser) and
//! rasterised to PNG from the same SVG, so both always agree.

pub mod b64;
pub mod draw;
pub mod error;
pub mod frames;
pub mod html;
pub mod outdir;
pub mod people;
pub mod pictures;
pub mod plots;
pub mod raster;
pub mod style;
pub mod svg;
pub mod timeline;

pub use error::{ReportError, Result};
pub use frames::{FrameStore, FrameStoreParams};
pub use html::{report_html, standard_cards, Card, ReportInput};
pub use outdir::OutputDir;
pub use people::{PeopleView, PersonRow, PersonView};
pub use pictures::{person_view, report_page, write_pictures, Analysed};
pub use plots::{joint_trajectory_svg, PlotParams};
pub use timeline::{timeline_svg, TimeAxis, TimelineParams};
