//! Generated source of every bundled model, one module per model, committed
//! so readers can see what eom-gen emits. A test fails when a file is stale;
//! refresh with `cargo run -p eom-gen --example regenerate`.

/// Model `andrews`, generated from `models/andrews.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod andrews;
/// Model `arm7`, generated from `models/arm7.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod arm7;
/// Model `arm7_flex`, generated from `models/arm7_flex.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod arm7_flex;
/// Model `bouncing_ball`, generated from `models/bouncing_ball.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod bouncing_ball;
/// Model `bricard`, generated from `models/bricard.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod bricard;
/// Model `double_pendulum`, generated from `models/double_pendulum.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod double_pendulum;
/// Model `fourbar`, generated from `models/fourbar.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod fourbar;
/// Model `fourbar_n2`, generated from `models/fourbar_n2.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod fourbar_n2;
/// Model `fourbar_n4`, generated from `models/fourbar_n4.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod fourbar_n4;
/// Model `free_body`, generated from `models/free_body.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod free_body;
/// Model `heavy_top`, generated from `models/heavy_top.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod heavy_top;
/// Model `hub_beam`, generated from `models/hub_beam.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod hub_beam;
/// Model `pendulum`, generated from `models/pendulum.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod pendulum;
/// Model `rolling_disk`, generated from `models/rolling_disk.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod rolling_disk;
/// Model `slider_crank`, generated from `models/slider_crank.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod slider_crank;
/// Model `slider_crank_driven`, generated from `models/slider_crank_driven.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod slider_crank_driven;
/// Model `slider_crank_flex`, generated from `models/slider_crank_flex.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod slider_crank_flex;
/// Model `slider_crank_simeon`, generated from `models/slider_crank_simeon.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod slider_crank_simeon;
/// Model `spin_up`, generated from `models/spin_up.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod spin_up;
/// Model `stewart`, generated from `models/stewart.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod stewart;
/// Model `stewart_driven`, generated from `models/stewart_driven.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod stewart_driven;
/// Model `whipple`, generated from `models/whipple.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod whipple;
/// Model `pendulum_rod`, generated from `models/ancf/pendulum_rod.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod pendulum_rod;
/// Model `fourbar_cable`, generated from `models/ancf/fourbar_cable.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod fourbar_cable;
/// Model `pendulum_peg`, generated from `models/ancf/pendulum_peg.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod pendulum_peg;
/// Model `arm7_derivatives`, generated from `tests/scenes/arm7_derivatives.scene.ron`.
#[rustfmt::skip] // formatted by prettyplease; stays byte-identical
pub mod arm7_derivatives;
