//! One control clock. `rigtwin_device::Rate::CONTROL` is its home, and `world`, `hil` and
//! the viewer derive their constants from it; the arm must not depend on the rig's code,
//! so it restates the rate, and this test holds the two equal: a clock that disagreed by
//! one hertz would shift every neural update against the controller's ticks.
use rigtwin_device::Rate;

#[test]
fn the_arm_runs_on_the_rigs_4_khz_clock() {
    // 000_* section 5.1: the rig's control loop runs at 4 kHz.
    assert_eq!(Rate::CONTROL.hz(), 4000);
    assert_eq!(rigtwin_arm::time::TICK_HZ, u64::from(Rate::CONTROL.hz()));
}
