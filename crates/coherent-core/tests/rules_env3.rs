//! Scene env3 (one room: restaurant 0, no doors; two robot arms on the bar counters).
//!
//! Every expected list below was derived by hand from `env3.json` and docs/semantics.md:
//! section 2 for observations, section 3 for action lists, section 4 for transitions.

mod common;

use std::sync::LazyLock;

use coherent_core::Reason;
use common::{Scene, with};

// Robots of env3.
const ARM_10: i64 = 18; // on bar counter 10
const ARM_11: i64 = 19; // on bar counter 11
const DOG: i64 = 20;
const QUAD: i64 = 21;

/// The dog's list in the restaurant when nothing is close and nothing low has moved:
/// coffee tables 4 and 5, sofas 6 and 7, ottomans 8 and 9 (all LOW_HEIGHT), and the
/// paper money 16 ON sofa 6. Dining tables 2, 3 and bar counters 10, 11 are HIGH_HEIGHT;
/// coffee maker 13, beer glass 14, beer bottle 15, cash register 17 and the basket 22
/// are ON_HIGH_SURFACE.
const DOG_BASE: &[&str] = &[
    "[movetowards] <coffee table>(4)",
    "[movetowards] <coffee table>(5)",
    "[movetowards] <sofa>(6)",
    "[movetowards] <sofa>(7)",
    "[movetowards] <ottoman>(8)",
    "[movetowards] <ottoman>(9)",
    "[movetowards] <paper money>(16)",
];

/// Task 17: everything but the coffee cup 12, which is INSIDE the CLOSED coffee maker.
const VIEW_17: &[i64] = &[
    0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23, 24,
];

/// Task 17: every edge of the file except `12 INSIDE 13` (the hidden coffee cup).
const VIEW_17_EDGES: &[(i64, &str, i64)] = &[
    (1, "INSIDE", 0),
    (2, "ON", 1),
    (3, "ON", 1),
    (4, "ON", 1),
    (5, "ON", 1),
    (6, "ON", 1),
    (7, "ON", 1),
    (8, "ON", 1),
    (9, "ON", 1),
    (10, "ON", 1),
    (11, "ON", 1),
    (13, "ON", 10),
    (14, "ON", 11),
    (15, "ON", 11),
    (16, "ON", 6),
    (17, "ON", 11),
    (18, "ON", 10),
    (18, "INSIDE", 0),
    (19, "ON", 11),
    (19, "INSIDE", 0),
    (20, "ON", 1),
    (20, "INSIDE", 0),
    (21, "ON", 10),
    (21, "INSIDE", 0),
    (21, "WITH", 22),
    (22, "ON", 10),
    (23, "ON", 5),
    (24, "ON", 11),
];

/// The start of task 17, built once (`common`).
static TASK17: LazyLock<Scene> = LazyLock::new(|| Scene::load("env3", 17));

#[test]
fn task17_starts_with_every_robot_seeing_all_but_the_cup_in_the_closed_coffee_maker() {
    let s = TASK17.clone();
    for robot in [ARM_10, ARM_11, DOG, QUAD] {
        s.expect_view(robot, VIEW_17);
        s.expect_edges(robot, VIEW_17_EDGES);
    }
    s.expect_actions(QUAD, &["[takeoff_from] <bar counter>(10)"]);
    s.expect_actions(DOG, &with(DOG_BASE, &["[movetowards] <cookie>(23)"], &[]));
    // ON bar counter 10: the coffee maker (CLOSED), the quadrotor and its basket
    // (OPEN_FOREVER, empty). The cup inside the coffee maker is not observed.
    s.expect_actions(ARM_10, &["[open] <coffee maker>(13)"]);
    // ON bar counter 11: beer glass, beer bottle, cash register (CLOSED), plastic bag
    // (OPEN_FOREVER container, not GRABABLE).
    s.expect_actions(
        ARM_11,
        &[
            "[grab] <beer glass>(14)",
            "[grab] <beer bottle>(15)",
            "[open] <cash register>(17)",
        ],
    );
}

#[test]
fn the_cookie_rides_the_basket_down_to_the_dog_and_back_up_to_the_arm() {
    let mut s = TASK17.clone();
    // The basket starts ON_HIGH_SURFACE (in the file) on the HIGH bar counter.
    s.expect_high(&[22], true);

    s.act(QUAD, "[takeoff_from] <bar counter>(10)");
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <bar counter>(10)",
            "[movetowards] <restaurant floor>(1)",
            "[movetowards] <dining table>(2)",
            "[movetowards] <dining table>(3)",
            "[movetowards] <bar counter>(11)",
        ],
    );
    s.refused(QUAD, "[land_on] <sofa>(6)", Reason::NotLandable);
    s.expect_seen_edges(ARM_10, &[(21, "ABOVE", 10), (21, "WITH", 22)]);
    s.expect_unseen_edges(ARM_10, &[(21, "ON", 10), (22, "ON", 10)]);
    s.expect_actions(ARM_10, &["[open] <coffee maker>(13)"]);

    // Landing on the LOW_HEIGHT floor: the basket loses ON_HIGH_SURFACE.
    s.act(QUAD, "[movetowards] <restaurant floor>(1)");
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <restaurant floor>(1)",
            "[movetowards] <dining table>(2)",
            "[movetowards] <dining table>(3)",
            "[movetowards] <bar counter>(10)",
            "[movetowards] <bar counter>(11)",
        ],
    );
    s.act(QUAD, "[land_on] <restaurant floor>(1)");
    s.expect_high(&[22], false);
    s.expect_seen_edges(DOG, &[(21, "ON", 1), (22, "ON", 1)]);
    s.expect_actions(QUAD, &["[takeoff_from] <restaurant floor>(1)"]);
    s.expect_actions(
        DOG,
        &with(
            DOG_BASE,
            &["[movetowards] <basket>(22)", "[movetowards] <cookie>(23)"],
            &[],
        ),
    );

    // The dog brings the cookie from the coffee table to the basket.
    s.act(DOG, "[movetowards] <coffee table>(5)");
    s.expect_seen_edges(DOG, &[(20, "CLOSE", 5), (20, "CLOSE", 23)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_BASE,
            &["[grab] <cookie>(23)", "[movetowards] <basket>(22)"],
            &["[movetowards] <coffee table>(5)"],
        ),
    );
    s.act(DOG, "[grab] <cookie>(23)");
    s.expect_actions(
        DOG,
        &with(
            DOG_BASE,
            &[
                "[puton] <cookie>(23) on <coffee table>(5)",
                "[movetowards] <basket>(22)",
            ],
            &["[movetowards] <coffee table>(5)"],
        ),
    );
    s.act(DOG, "[movetowards] <basket>(22)");
    s.expect_actions(
        DOG,
        &with(DOG_BASE, &["[putinto] <cookie>(23) into <basket>(22)"], &[]),
    );
    s.act(DOG, "[putinto] <cookie>(23) into <basket>(22)");
    s.expect_seen_edges(
        DOG,
        &[(23, "INSIDE", 22), (20, "CLOSE", 22), (20, "CLOSE", 23)],
    );
    s.expect_actions(DOG, &with(DOG_BASE, &["[grab] <cookie>(23)"], &[]));

    // Up again: basket and cookie ON_HIGH_SURFACE, the dog's CLOSE edges to them gone.
    s.act(QUAD, "[takeoff_from] <restaurant floor>(1)");
    s.expect_high(&[22, 23], true);
    s.expect_unseen_edges(DOG, &[(20, "CLOSE", 22), (20, "CLOSE", 23)]);
    s.expect_actions(DOG, DOG_BASE);
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <restaurant floor>(1)",
            "[movetowards] <dining table>(2)",
            "[movetowards] <dining table>(3)",
            "[movetowards] <bar counter>(10)",
            "[movetowards] <bar counter>(11)",
        ],
    );

    // Landing on bar counter 11 (HIGH_HEIGHT), next to the second arm.
    s.act(QUAD, "[movetowards] <bar counter>(11)");
    s.act(QUAD, "[land_on] <bar counter>(11)");
    s.expect_high(&[22, 23], true);
    s.expect_seen_edges(
        ARM_11,
        &[(21, "ON", 11), (22, "ON", 11), (23, "INSIDE", 22)],
    );
    s.expect_actions(
        ARM_11,
        &[
            "[grab] <beer glass>(14)",
            "[grab] <beer bottle>(15)",
            "[open] <cash register>(17)",
            "[grab] <cookie>(23)",
        ],
    );
    s.expect_actions(ARM_10, &["[open] <coffee maker>(13)"]);
    s.refused(ARM_10, "[grab] <cookie>(23)", Reason::OutOfReach);

    // The arm moves the cookie from the basket into the plastic bag: task done.
    s.act(ARM_11, "[grab] <cookie>(23)");
    s.expect_unseen_edges(ARM_11, &[(23, "INSIDE", 22)]);
    s.expect_actions(
        ARM_11,
        &[
            "[puton] <cookie>(23) on <bar counter>(11)",
            "[putinto] <cookie>(23) into <basket>(22)",
            "[putinto] <cookie>(23) into <plastic bag>(24)",
        ],
    );
    let out = s.act(ARM_11, "[putinto] <cookie>(23) into <plastic bag>(24)");
    assert!(out.done);
    s.expect_seen_edges(QUAD, &[(23, "INSIDE", 24), (24, "ON", 11)]);
    s.expect_actions(
        ARM_11,
        &[
            "[grab] <beer glass>(14)",
            "[grab] <beer bottle>(15)",
            "[open] <cash register>(17)",
            "[grab] <cookie>(23)",
        ],
    );
}

#[test]
fn the_coffee_cup_comes_out_of_the_coffee_maker_and_down_to_the_dog_in_the_basket() {
    let mut s = TASK17.clone();
    s.act(ARM_10, "[open] <coffee maker>(13)");
    assert_eq!(s.states(13), ["OPEN"]);
    let mut all = VIEW_17.to_vec();
    all.push(12);
    s.expect_view(DOG, &all);
    s.expect_seen_edges(DOG, &[(12, "INSIDE", 13)]);
    // The cup is ON_HIGH_SURFACE (in the file): nothing new for the dog.
    s.expect_actions(DOG, &with(DOG_BASE, &["[movetowards] <cookie>(23)"], &[]));
    s.expect_actions(
        ARM_10,
        &["[close] <coffee maker>(13)", "[grab] <coffee cup>(12)"],
    );

    // The arm puts the cup into the basket of the quadrotor landed beside it.
    s.act(ARM_10, "[grab] <coffee cup>(12)");
    s.expect_actions(
        ARM_10,
        &[
            "[puton] <coffee cup>(12) on <bar counter>(10)",
            "[putinto] <coffee cup>(12) into <coffee maker>(13)",
            "[putinto] <coffee cup>(12) into <basket>(22)",
        ],
    );
    s.act(ARM_10, "[putinto] <coffee cup>(12) into <basket>(22)");
    s.expect_seen_edges(QUAD, &[(12, "INSIDE", 22)]);
    s.expect_actions(
        ARM_10,
        &["[close] <coffee maker>(13)", "[grab] <coffee cup>(12)"],
    );

    // Flown down to the floor, the cup loses ON_HIGH_SURFACE with the basket.
    s.act(QUAD, "[takeoff_from] <bar counter>(10)");
    s.expect_actions(ARM_10, &["[close] <coffee maker>(13)"]);
    s.act(QUAD, "[movetowards] <restaurant floor>(1)");
    s.act(QUAD, "[land_on] <restaurant floor>(1)");
    s.expect_high(&[12, 22], false);
    s.expect_view(DOG, &all);
    s.expect_seen_edges(DOG, &[(12, "INSIDE", 22), (22, "ON", 1), (21, "ON", 1)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_BASE,
            &[
                "[movetowards] <coffee cup>(12)",
                "[movetowards] <basket>(22)",
                "[movetowards] <cookie>(23)",
            ],
            &[],
        ),
    );

    // Moving to the cup inside the open basket: close to the cup and to the basket.
    s.act(DOG, "[movetowards] <coffee cup>(12)");
    s.expect_seen_edges(DOG, &[(20, "CLOSE", 12), (20, "CLOSE", 22)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_BASE,
            &["[grab] <coffee cup>(12)", "[movetowards] <cookie>(23)"],
            &[],
        ),
    );
    s.act(DOG, "[grab] <coffee cup>(12)");
    s.expect_actions(
        DOG,
        &with(
            DOG_BASE,
            &[
                "[putinto] <coffee cup>(12) into <basket>(22)",
                "[movetowards] <cookie>(23)",
            ],
            &[],
        ),
    );
    // To the sofa with the paper money ON it.
    s.act(DOG, "[movetowards] <sofa>(6)");
    s.expect_seen_edges(
        DOG,
        &[(20, "CLOSE", 6), (20, "CLOSE", 16), (20, "HOLD", 12)],
    );
    s.expect_unseen_edges(DOG, &[(20, "CLOSE", 22), (20, "CLOSE", 1)]);
    s.expect_actions(
        DOG,
        &with(
            DOG_BASE,
            &[
                "[puton] <coffee cup>(12) on <sofa>(6)",
                "[movetowards] <basket>(22)",
                "[movetowards] <cookie>(23)",
            ],
            &["[movetowards] <sofa>(6)", "[movetowards] <paper money>(16)"],
        ),
    );
    s.act(DOG, "[puton] <coffee cup>(12) on <sofa>(6)");
    s.expect_seen_edges(DOG, &[(12, "ON", 6)]);
    s.expect_high(&[12], false);
}

/// Task 2: the quadrotor waits on bar counter 11 for milk and bread in its basket.
#[test]
fn filling_the_basket_landed_on_the_arms_counter_completes_task2_and_the_flight_takes_it_to_the_other_arm()
 {
    let mut s = Scene::load("env3", 2);
    // Everything but the coffee cup 12, hidden in the CLOSED coffee maker.
    let view: Vec<i64> = (0..=24).filter(|&n| n != 12).collect();
    for robot in [ARM_10, ARM_11, DOG, QUAD] {
        s.expect_view(robot, &view);
    }
    s.expect_seen_edges(
        QUAD,
        &[
            (21, "ON", 11),
            (21, "INSIDE", 0),
            (21, "WITH", 22),
            (22, "ON", 11),
            (23, "ON", 11),
            (24, "ON", 11),
        ],
    );
    s.expect_unseen_edges(QUAD, &[(12, "INSIDE", 13)]);
    s.expect_actions(QUAD, &["[takeoff_from] <bar counter>(11)"]);
    s.expect_actions(DOG, DOG_BASE);
    s.expect_actions(ARM_10, &["[open] <coffee maker>(13)"]);
    s.expect_actions(
        ARM_11,
        &[
            "[grab] <beer glass>(14)",
            "[grab] <beer bottle>(15)",
            "[open] <cash register>(17)",
            "[grab] <bottle of milk>(23)",
            "[grab] <bread>(24)",
        ],
    );

    s.act(ARM_11, "[grab] <bottle of milk>(23)");
    s.expect_actions(
        ARM_11,
        &[
            "[puton] <bottle of milk>(23) on <bar counter>(11)",
            "[putinto] <bottle of milk>(23) into <basket>(22)",
        ],
    );
    s.refused(
        ARM_11,
        "[putinto] <bottle of milk>(23) into <cash register>(17)",
        Reason::ContainerClosed,
    );
    s.refused(ARM_11, "[grab] <bread>(24)", Reason::HandFull);
    s.act(ARM_11, "[putinto] <bottle of milk>(23) into <basket>(22)");
    s.expect_actions(
        ARM_11,
        &[
            "[grab] <beer glass>(14)",
            "[grab] <beer bottle>(15)",
            "[open] <cash register>(17)",
            "[grab] <bottle of milk>(23)",
            "[grab] <bread>(24)",
        ],
    );
    s.act(ARM_11, "[grab] <bread>(24)");
    s.expect_actions(
        ARM_11,
        &[
            "[puton] <bread>(24) on <bar counter>(11)",
            "[putinto] <bread>(24) into <basket>(22)",
        ],
    );
    let out = s.act(ARM_11, "[putinto] <bread>(24) into <basket>(22)");
    assert!(out.done);
    s.expect_seen_edges(QUAD, &[(23, "INSIDE", 22), (24, "INSIDE", 22)]);

    // The basket leaves arm 19's counter and lands beside arm 18.
    s.act(QUAD, "[takeoff_from] <bar counter>(11)");
    s.expect_actions(
        ARM_11,
        &[
            "[grab] <beer glass>(14)",
            "[grab] <beer bottle>(15)",
            "[open] <cash register>(17)",
        ],
    );
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <bar counter>(11)",
            "[movetowards] <restaurant floor>(1)",
            "[movetowards] <dining table>(2)",
            "[movetowards] <dining table>(3)",
            "[movetowards] <bar counter>(10)",
        ],
    );
    s.act(QUAD, "[movetowards] <bar counter>(10)");
    s.act(QUAD, "[land_on] <bar counter>(10)");
    s.expect_actions(
        ARM_10,
        &[
            "[open] <coffee maker>(13)",
            "[grab] <bottle of milk>(23)",
            "[grab] <bread>(24)",
        ],
    );
    s.expect_actions(DOG, DOG_BASE);
}

#[test]
fn each_refusal_in_the_restaurant_gives_its_own_reason() {
    let mut s = TASK17.clone();
    s.refused(DOG, "[grab] <cookie>(23)", Reason::NotClose);
    s.refused(DOG, "[movetowards] <bar counter>(10)", Reason::TooHigh);
    s.refused(DOG, "[movetowards] <plastic bag>(24)", Reason::TooHigh);
    s.refused(DOG, "[movetowards] <quadrotor>(21)", Reason::NotATarget);
    s.refused(ARM_11, "[grab] <coffee cup>(12)", Reason::NotInView);
    s.refused(ARM_11, "[grab] <cookie>(23)", Reason::OutOfReach);
    s.refused(ARM_11, "[open] <plastic bag>(24)", Reason::AlreadyOpen);
    s.refused(ARM_11, "[grab] <plastic bag>(24)", Reason::NotGrabable);
    s.refused(ARM_10, "[open] <bar counter>(10)", Reason::NotOpenable);
    s.refused(
        QUAD,
        "[takeoff_from] <bar counter>(11)",
        Reason::NotOnSurface,
    );
    s.refused(QUAD, "[grab] <cookie>(23)", Reason::WrongRobotType);
    s.refused(DOG, "[grab] <cookie>(99)", Reason::NoSuchNode);
    s.refused(DOG, "[grab] <biscuit>(23)", Reason::NoSuchNode);
    s.refused(DOG, "grab the cookie", Reason::Unparsable);
}
