//! mp-forecast
