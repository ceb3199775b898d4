//! Fractional Gaussian field synthesis (issue 3). See ARCHITECTURE.md.
