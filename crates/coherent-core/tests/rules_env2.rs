//! Scene env2 (one room: grocery store 0, no doors).
//!
//! Every expected list below was derived by hand from `env2.json` and docs/semantics.md:
//! section 2 for observations, section 3 for action lists, section 4 for transitions.

mod common;

use std::sync::LazyLock;

use coherent_core::Reason;
use common::Scene;

// Robots of env2.
const ARM_DISPLAY: i64 = 18; // on the display table (5)
const ARM_CHECKOUT: i64 = 19; // on the checkout counter (8)
const DOG: i64 = 20;
const QUAD: i64 = 21;

/// Task 16: with a single room and every container open (display bins and the carton
/// are OPEN_FOREVER, the cash register is CLOSED but empty), every robot sees all 26
/// nodes.
const ALL_16: &[i64] = &[
    0, 1, 2, 3, 4, 5, 6, 7, 8, 13, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 29, 30, 38, 41, 42, 44,
];

/// Task 16: every edge of the file.
const ALL_16_EDGES: &[(i64, &str, i64)] = &[
    (1, "INSIDE", 0),
    (2, "ON", 5),
    (3, "ON", 5),
    (4, "ON", 5),
    (5, "ON", 1),
    (6, "ON", 1),
    (7, "ON", 1),
    (8, "ON", 1),
    (13, "INSIDE", 3),
    (18, "ON", 5),
    (18, "INSIDE", 0),
    (19, "ON", 8),
    (19, "INSIDE", 0),
    (20, "ON", 1),
    (20, "INSIDE", 0),
    (21, "ON", 1),
    (21, "INSIDE", 0),
    (21, "WITH", 22),
    (22, "ON", 1),
    (23, "ON", 1),
    (24, "ON", 8),
    (25, "ON", 7),
    (26, "ON", 1),
    (27, "INSIDE", 26),
    (29, "ON", 1),
    (30, "ON", 8),
    (38, "ON", 1),
    (41, "ON", 1),
    (42, "ON", 1),
    (44, "INSIDE", 26),
];

/// The start of task 16, built once (`common`).
static TASK16: LazyLock<Scene> = LazyLock::new(|| Scene::load("env2", 16));

#[test]
fn task16_starts_with_every_robot_seeing_the_whole_grocery_store() {
    let s = TASK16.clone();
    for robot in [ARM_DISPLAY, ARM_CHECKOUT, DOG, QUAD] {
        s.expect_view(robot, ALL_16);
        s.expect_edges(robot, ALL_16_EDGES);
    }
    s.expect_actions(QUAD, &["[takeoff_from] <grocery store floor>(1)"]);
    // Not offered: display tables 5 and 42 and the checkout counter 8 (HIGH_HEIGHT),
    // display bins 2-4, lettuce 13, cash register 24, shopping basket 30
    // (ON_HIGH_SURFACE). No doors, so no rooms.
    s.expect_actions(
        DOG,
        &[
            "[movetowards] <pedestal table>(6)",
            "[movetowards] <pedestal table>(7)",
            "[movetowards] <basket>(22)",
            "[movetowards] <trash can>(23)",
            "[movetowards] <paper money>(25)",
            "[movetowards] <carton>(26)",
            "[movetowards] <pack of bread>(27)",
            "[movetowards] <grocery shelf>(29)",
            "[movetowards] <trash can>(38)",
            "[movetowards] <bucket>(41)",
            "[movetowards] <apple>(44)",
        ],
    );
    // Display bins 2-4 are ON its table; lettuce 13 is INSIDE bin 3.
    s.expect_actions(ARM_DISPLAY, &["[grab] <lettuce>(13)"]);
    // Cash register 24 (CLOSED) and shopping basket 30 (OPEN_FOREVER) are ON its counter.
    s.expect_actions(ARM_CHECKOUT, &["[open] <cash register>(24)"]);
}

#[test]
fn the_checkout_arm_opens_and_closes_the_cash_register_but_not_twice() {
    let mut s = TASK16.clone();
    s.act(ARM_CHECKOUT, "[open] <cash register>(24)");
    assert_eq!(s.states(24), ["OPEN"]);
    s.expect_actions(ARM_CHECKOUT, &["[close] <cash register>(24)"]);
    s.act(ARM_CHECKOUT, "[close] <cash register>(24)");
    assert_eq!(s.states(24), ["CLOSED"]);
    s.expect_actions(ARM_CHECKOUT, &["[open] <cash register>(24)"]);
    s.refused(
        ARM_CHECKOUT,
        "[close] <cash register>(24)",
        Reason::AlreadyClosed,
    );
}

#[test]
fn the_apple_rides_the_basket_to_the_display_bin_and_the_bread_to_the_pedestal_completes_task16() {
    let mut s = TASK16.clone();

    // The dog moves to the apple INSIDE the open carton: close to both.
    s.act(DOG, "[movetowards] <apple>(44)");
    s.expect_seen_edges(DOG, &[(20, "CLOSE", 44), (20, "CLOSE", 26)]);
    s.expect_actions(
        DOG,
        &[
            "[grab] <apple>(44)",
            "[movetowards] <pedestal table>(6)",
            "[movetowards] <pedestal table>(7)",
            "[movetowards] <basket>(22)",
            "[movetowards] <trash can>(23)",
            "[movetowards] <paper money>(25)",
            "[movetowards] <pack of bread>(27)",
            "[movetowards] <grocery shelf>(29)",
            "[movetowards] <trash can>(38)",
            "[movetowards] <bucket>(41)",
        ],
    );
    s.act(DOG, "[grab] <apple>(44)");
    s.expect_unseen_edges(DOG, &[(44, "INSIDE", 26)]);
    s.expect_actions(
        DOG,
        &[
            "[putinto] <apple>(44) into <carton>(26)",
            "[movetowards] <pedestal table>(6)",
            "[movetowards] <pedestal table>(7)",
            "[movetowards] <basket>(22)",
            "[movetowards] <trash can>(23)",
            "[movetowards] <paper money>(25)",
            "[movetowards] <pack of bread>(27)",
            "[movetowards] <grocery shelf>(29)",
            "[movetowards] <trash can>(38)",
            "[movetowards] <bucket>(41)",
        ],
    );
    s.act(DOG, "[movetowards] <basket>(22)");
    s.expect_actions(
        DOG,
        &[
            "[putinto] <apple>(44) into <basket>(22)",
            "[movetowards] <pedestal table>(6)",
            "[movetowards] <pedestal table>(7)",
            "[movetowards] <trash can>(23)",
            "[movetowards] <paper money>(25)",
            "[movetowards] <carton>(26)",
            "[movetowards] <pack of bread>(27)",
            "[movetowards] <grocery shelf>(29)",
            "[movetowards] <trash can>(38)",
            "[movetowards] <bucket>(41)",
        ],
    );
    s.act(DOG, "[putinto] <apple>(44) into <basket>(22)");
    s.expect_actions(
        DOG,
        &[
            "[grab] <apple>(44)",
            "[movetowards] <pedestal table>(6)",
            "[movetowards] <pedestal table>(7)",
            "[movetowards] <trash can>(23)",
            "[movetowards] <paper money>(25)",
            "[movetowards] <carton>(26)",
            "[movetowards] <pack of bread>(27)",
            "[movetowards] <grocery shelf>(29)",
            "[movetowards] <trash can>(38)",
            "[movetowards] <bucket>(41)",
        ],
    );

    // Take-off: the dog loses the basket and the apple.
    s.act(QUAD, "[takeoff_from] <grocery store floor>(1)");
    s.expect_high(&[22, 44], true);
    s.expect_view(DOG, ALL_16);
    s.expect_seen_edges(DOG, &[(21, "ABOVE", 1), (44, "INSIDE", 22)]);
    s.expect_unseen_edges(DOG, &[(20, "CLOSE", 22), (20, "CLOSE", 44), (22, "ON", 1)]);
    s.expect_actions(
        DOG,
        &[
            "[movetowards] <pedestal table>(6)",
            "[movetowards] <pedestal table>(7)",
            "[movetowards] <trash can>(23)",
            "[movetowards] <paper money>(25)",
            "[movetowards] <carton>(26)",
            "[movetowards] <pack of bread>(27)",
            "[movetowards] <grocery shelf>(29)",
            "[movetowards] <trash can>(38)",
            "[movetowards] <bucket>(41)",
        ],
    );
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <grocery store floor>(1)",
            "[movetowards] <display table>(5)",
            "[movetowards] <checkout counter>(8)",
            "[movetowards] <display table>(42)",
        ],
    );
    s.refused(QUAD, "[land_on] <pedestal table>(6)", Reason::NotLandable);

    // Landing on the display table, next to the arm that reaches into the basket.
    s.act(QUAD, "[movetowards] <display table>(5)");
    s.act(QUAD, "[land_on] <display table>(5)");
    s.expect_high(&[22, 44], true);
    s.expect_actions(QUAD, &["[takeoff_from] <display table>(5)"]);
    s.expect_seen_edges(QUAD, &[(21, "ON", 5), (22, "ON", 5), (44, "INSIDE", 22)]);
    s.expect_unseen_edges(QUAD, &[(21, "ABOVE", 5), (21, "ON", 1)]);
    s.expect_actions(ARM_DISPLAY, &["[grab] <lettuce>(13)", "[grab] <apple>(44)"]);
    s.expect_actions(ARM_CHECKOUT, &["[open] <cash register>(24)"]);
    s.refused(ARM_CHECKOUT, "[grab] <apple>(44)", Reason::OutOfReach);

    s.act(ARM_DISPLAY, "[grab] <apple>(44)");
    s.expect_actions(
        ARM_DISPLAY,
        &[
            "[puton] <apple>(44) on <display table>(5)",
            "[putinto] <apple>(44) into <display bin>(2)",
            "[putinto] <apple>(44) into <display bin>(3)",
            "[putinto] <apple>(44) into <display bin>(4)",
            "[putinto] <apple>(44) into <basket>(22)",
        ],
    );
    let out = s.act(ARM_DISPLAY, "[putinto] <apple>(44) into <display bin>(2)");
    assert!(!out.done, "the pack of bread is still in the carton");
    s.expect_seen_edges(DOG, &[(44, "INSIDE", 2)]);
    s.expect_high(&[44], true);
    s.expect_actions(ARM_DISPLAY, &["[grab] <lettuce>(13)", "[grab] <apple>(44)"]);

    // Back down on the LOW_HEIGHT floor: the empty basket loses ON_HIGH_SURFACE.
    s.act(QUAD, "[takeoff_from] <display table>(5)");
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <display table>(5)",
            "[movetowards] <grocery store floor>(1)",
            "[movetowards] <checkout counter>(8)",
            "[movetowards] <display table>(42)",
        ],
    );
    s.act(QUAD, "[movetowards] <grocery store floor>(1)");
    s.act(QUAD, "[land_on] <grocery store floor>(1)");
    s.expect_high(&[22], false);
    s.expect_high(&[44], true);
    s.expect_actions(
        DOG,
        &[
            "[movetowards] <pedestal table>(6)",
            "[movetowards] <pedestal table>(7)",
            "[movetowards] <basket>(22)",
            "[movetowards] <trash can>(23)",
            "[movetowards] <paper money>(25)",
            "[movetowards] <carton>(26)",
            "[movetowards] <pack of bread>(27)",
            "[movetowards] <grocery shelf>(29)",
            "[movetowards] <trash can>(38)",
            "[movetowards] <bucket>(41)",
        ],
    );

    // The dog puts the pack of bread on the pedestal table, which ends the task.
    s.act(DOG, "[movetowards] <pack of bread>(27)");
    s.expect_actions(
        DOG,
        &[
            "[grab] <pack of bread>(27)",
            "[movetowards] <pedestal table>(6)",
            "[movetowards] <pedestal table>(7)",
            "[movetowards] <basket>(22)",
            "[movetowards] <trash can>(23)",
            "[movetowards] <paper money>(25)",
            "[movetowards] <grocery shelf>(29)",
            "[movetowards] <trash can>(38)",
            "[movetowards] <bucket>(41)",
        ],
    );
    s.act(DOG, "[grab] <pack of bread>(27)");
    s.act(DOG, "[movetowards] <pedestal table>(6)");
    s.expect_actions(
        DOG,
        &[
            "[puton] <pack of bread>(27) on <pedestal table>(6)",
            "[movetowards] <pedestal table>(7)",
            "[movetowards] <basket>(22)",
            "[movetowards] <trash can>(23)",
            "[movetowards] <paper money>(25)",
            "[movetowards] <carton>(26)",
            "[movetowards] <grocery shelf>(29)",
            "[movetowards] <trash can>(38)",
            "[movetowards] <bucket>(41)",
        ],
    );
    let out = s.act(DOG, "[puton] <pack of bread>(27) on <pedestal table>(6)");
    assert!(out.done);
}

#[test]
fn each_refusal_in_the_grocery_store_gives_its_own_reason() {
    let mut s = TASK16.clone();
    s.refused(DOG, "[grab] <apple>(44)", Reason::NotClose);
    s.refused(DOG, "[movetowards] <display table>(5)", Reason::TooHigh);
    s.refused(DOG, "[movetowards] <display bin>(2)", Reason::TooHigh);
    s.refused(
        DOG,
        "[movetowards] <grocery store floor>(1)",
        Reason::NotATarget,
    );
    s.refused(DOG, "[open] <carton>(26)", Reason::AlreadyOpen);
    s.refused(ARM_DISPLAY, "[grab] <apple>(44)", Reason::OutOfReach);
    s.refused(
        ARM_DISPLAY,
        "[putinto] <lettuce>(13) into <display bin>(2)",
        Reason::HandEmpty,
    );
    s.refused(
        ARM_DISPLAY,
        "[movetowards] <apple>(44)",
        Reason::WrongRobotType,
    );
    s.refused(QUAD, "[movetowards] <display table>(5)", Reason::NotFlying);
    s.act(QUAD, "[takeoff_from] <grocery store floor>(1)");
    s.refused(QUAD, "[land_on] <grocery shelf>(29)", Reason::NotLandable);
    s.refused(QUAD, "[land_on] <display table>(42)", Reason::NotAbove);
    s.refused(
        QUAD,
        "[movetowards] <grocery store>(0)",
        Reason::AlreadyThere,
    );
}
