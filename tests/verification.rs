//! Verification suite: each test states the requirement it checks and its
//! source (SPEC section, paper equation or figure).

mod verification {
    pub mod units;
}
