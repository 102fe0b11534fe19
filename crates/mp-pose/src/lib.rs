//! mp-pose
