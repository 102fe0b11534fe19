//! Library errors as Python exceptions: one exception type per error family,
//! all deriving from `MpError`, each carrying the library's message.

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

create_exception!(
    motion_programs,
    ForecastError,
    MpError,
    "Forecasting (prediction of future frames) failed."
);
create_exception!(
    motion_programs,
    RefineError,
    MpError,
    "Motion refinement failed."
);

create_exception!(
    motion_programs,
    MpError,
    PyException,
    "Base class of every error raised by motion_programs."
);
create_exception!(
    motion_programs,
    TrackError,
    MpError,
    "A track or file of keypoints is invalid or cannot be read or written."
);
create_exception!(
    motion_programs,
    PoseError,
    MpError,
    "Video decoding or pose estimation failed."
);
create_exception!(
    motion_programs,
    ProgramError,
    MpError,
    "A concrete program cannot be fitted, parsed or executed."
);
create_exception!(
    motion_programs,
    AbstractError,
    MpError,
    "An abstract program, loop detection or repetition counting failed."
);
create_exception!(
    motion_programs,
    GrammarError,
    MpError,
    "Motion grammar: symbols or grammar learning failed."
);
create_exception!(
    motion_programs,
    ParamError,
    MpError,
    "A parameter is out of its valid range."
);
create_exception!(
    motion_programs,
    CancelledError,
    MpError,
    "The run was cancelled."
);
create_exception!(
    motion_programs,
    OutputError,
    MpError,
    "Pictures, report or the output folder could not be written."
);

/// Registers the exception types on the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("MpError", py.get_type::<MpError>())?;
    m.add("TrackError", py.get_type::<TrackError>())?;
    m.add("PoseError", py.get_type::<PoseError>())?;
    m.add("ProgramError", py.get_type::<ProgramError>())?;
    m.add("AbstractError", py.get_type::<AbstractError>())?;
    m.add("GrammarError", py.get_type::<GrammarError>())?;
    m.add("ForecastError", py.get_type::<ForecastError>())?;
    m.add("RefineError", py.get_type::<RefineError>())?;
    m.add("ParamError", py.get_type::<ParamError>())?;
    m.add("CancelledError", py.get_type::<CancelledError>())?;
    m.add("OutputError", py.get_type::<OutputError>())?;
    Ok(())
}

/// A geometry / track error.
pub fn geom(e: mp_geom::GeomError) -> PyErr {
    TrackError::new_err(e.to_string())
}

/// A concrete-program error.
pub fn concrete(e: mp_concrete::ConcreteError) -> PyErr {
    ProgramError::new_err(e.to_string())
}

/// A grammar error.
pub fn grammar(e: mp_grammar::GrammarError) -> PyErr {
    GrammarError::new_err(e.to_string())
}

/// A forecasting error.
pub fn forecast(e: mp_forecast::ForecastError) -> PyErr {
    ForecastError::new_err(e.to_string())
}

/// A refinement error.
pub fn refine(e: mp_refine::RefineError) -> PyErr {
    RefineError::new_err(e.to_string())
}

/// A pipeline error, raised as the family of the library that failed.
pub fn pipeline(e: mp_pipeline::PipelineError) -> PyErr {
    use mp_pipeline::PipelineError as P;
    let msg = e.to_string();
    match e {
        P::Cancelled => CancelledError::new_err(msg),
        P::MissingInput(_) | P::Track { .. } | P::Geom(_) | P::TooShort(_) => {
            TrackError::new_err(msg)
        }
        P::Param { .. }
        | P::Concrete(mp_concrete::ConcreteError::InvalidParam { .. })
        | P::Pose(mp_pose::PoseError::InvalidParam { .. }) => ParamError::new_err(msg),
        P::Pose(_) => PoseError::new_err(msg),
        P::Concrete(_) => ProgramError::new_err(msg),
        P::Abstract(_) => AbstractError::new_err(msg),
        P::Report(_) | P::Json(_) => OutputError::new_err(msg),
        P::Stage { ref stage, .. } if stage.contains("concrete") => ProgramError::new_err(msg),
        P::Stage { ref stage, .. } if stage.contains("loops") => AbstractError::new_err(msg),
        P::Stage { .. } => MpError::new_err(msg),
        // An error kind added later: the base class.
        _ => MpError::new_err(msg),
    }
}

/// A batch error: its parameters (`ParamError`), its run parameters (as
/// [`pipeline`]), or an output folder or manifest it cannot write (`OutputError`).
pub fn batch(e: mp_pipeline::BatchError) -> PyErr {
    use mp_pipeline::BatchError as B;
    let msg = e.to_string();
    match e {
        B::Param { .. } => ParamError::new_err(msg),
        B::Pipeline(p) => pipeline(p),
        _ => OutputError::new_err(msg),
    }
}
