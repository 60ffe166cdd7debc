//! Analytic backend
