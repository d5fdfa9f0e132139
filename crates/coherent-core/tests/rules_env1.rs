//! Scene env1 (livingroom 0, kitchen 2, utility room 34; door 24 between livingroom and
//! kitchen is OPEN_FOREVER, door 35 between livingroom and utility room starts CLOSED).
//!
//! Every expected list below was derived by hand from `env1.json` and docs/semantics.md:
//! section 2 for observations, section 3 for action lists, section 4 for transitions.

mod common;

use std::sync::LazyLock;

use coherent_core::Reason;
use common::Scene;

// Robots of env1.
const ARM: i64 = 20; // on the kitchen table (11)
const DOG: i64 = 21;
const QUAD: i64 = 22;
const ARM_DINING: i64 = 44; // on the dining table (9)

/// Task 7, livingroom (0): floor 1 with coffee table 4, chairs 5 and 6, the dog, the
/// quadrotor, basket 23, low bookshelves 36 and 37; cookbook 28 ON bookshelf 36, beer
/// glass 53 ON the coffee table; doors 24 and 35; the three rooms.
const LIVINGROOM_7: &[i64] = &[0, 1, 2, 4, 5, 6, 21, 22, 23, 24, 28, 34, 35, 36, 37, 53];

const LIVINGROOM_7_EDGES: &[(i64, &str, i64)] = &[
    (1, "INSIDE", 0),
    (4, "ON", 1),
    (5, "ON", 1),
    (6, "ON", 1),
    (21, "ON", 1),
    (21, "INSIDE", 0),
    (22, "ON", 1),
    (22, "INSIDE", 0),
    (22, "WITH", 23),
    (23, "ON", 1),
    (24, "LEADING TO", 0),
    (24, "LEADING TO", 2),
    (28, "ON", 36),
    (35, "LEADING TO", 0),
    (35, "LEADING TO", 34),
    (36, "ON", 1),
    (37, "ON", 1),
    (53, "ON", 4),
];

/// Task 7, kitchen (2) without the quadrotor: floor 3 with fridge 7 (empty), dining
/// table 9, kitchen table 11, cleaning supplies 41, trash can 47; sink 8, burner 10,
/// tomato sauce jar 18 and arm 20 ON the kitchen table; fruit bowl 30 and arm 44 ON the
/// dining table; door 24; the three rooms.
const KITCHEN_7: &[i64] = &[0, 2, 3, 7, 8, 9, 10, 11, 18, 20, 24, 30, 34, 41, 44, 47];

const KITCHEN_7_EDGES: &[(i64, &str, i64)] = &[
    (3, "INSIDE", 2),
    (7, "ON", 3),
    (8, "ON", 11),
    (9, "ON", 3),
    (10, "ON", 11),
    (11, "ON", 3),
    (18, "ON", 11),
    (20, "ON", 11),
    (20, "INSIDE", 2),
    (24, "LEADING TO", 0),
    (24, "LEADING TO", 2),
    (30, "ON", 9),
    (41, "ON", 3),
    (44, "ON", 9),
    (44, "INSIDE", 2),
    (47, "ON", 3),
];

/// The start of task 7, built once (`common`).
static TASK7: LazyLock<Scene> = LazyLock::new(|| Scene::load("env1", 7));

#[test]
fn task7_starts_with_each_robot_seeing_its_room_and_offered_what_it_reaches() {
    let s = TASK7.clone();
    for robot in [DOG, QUAD] {
        s.expect_view(robot, LIVINGROOM_7);
        s.expect_edges(robot, LIVINGROOM_7_EDGES);
    }
    for robot in [ARM, ARM_DINING] {
        s.expect_view(robot, KITCHEN_7);
        s.expect_edges(robot, KITCHEN_7_EDGES);
    }
    s.expect_actions(QUAD, &["[takeoff_from] <livingroom floor>(1)"]);
    // Door 35 is CLOSED: no utility room. Doors are things to move to.
    s.expect_actions(
        DOG,
        &[
            "[movetowards] <coffee table>(4)",
            "[movetowards] <chair>(5)",
            "[movetowards] <chair>(6)",
            "[movetowards] <basket>(23)",
            "[movetowards] <door>(24)",
            "[movetowards] <cookbook>(28)",
            "[movetowards] <door>(35)",
            "[movetowards] <low bookshelf>(36)",
            "[movetowards] <low bookshelf>(37)",
            "[movetowards] <beer glass>(53)",
            "[movetowards] <kitchen>(2)",
        ],
    );
    // Sink 8 (OPEN_FOREVER) and burner 10 offer nothing to an empty hand.
    s.expect_actions(ARM, &["[grab] <tomato sauce jar>(18)"]);
    s.expect_actions(ARM_DINING, &["[grab] <fruit bowl>(30)"]);
}

#[test]
fn the_cookbook_rides_the_basket_to_the_kitchen_table_and_landing_there_completes_task7() {
    let mut s = TASK7.clone();

    // The dog moves to the bookshelf (a surface): the cookbook ON it becomes CLOSE.
    s.act(DOG, "[movetowards] <low bookshelf>(36)");
    s.expect_seen_edges(DOG, &[(21, "CLOSE", 36), (21, "CLOSE", 28)]);
    s.expect_actions(
        DOG,
        &[
            "[grab] <cookbook>(28)",
            "[movetowards] <coffee table>(4)",
            "[movetowards] <chair>(5)",
            "[movetowards] <chair>(6)",
            "[movetowards] <basket>(23)",
            "[movetowards] <door>(24)",
            "[movetowards] <door>(35)",
            "[movetowards] <low bookshelf>(37)",
            "[movetowards] <beer glass>(53)",
            "[movetowards] <kitchen>(2)",
        ],
    );
    s.act(DOG, "[grab] <cookbook>(28)");
    s.expect_actions(
        DOG,
        &[
            "[puton] <cookbook>(28) on <low bookshelf>(36)",
            "[movetowards] <coffee table>(4)",
            "[movetowards] <chair>(5)",
            "[movetowards] <chair>(6)",
            "[movetowards] <basket>(23)",
            "[movetowards] <door>(24)",
            "[movetowards] <door>(35)",
            "[movetowards] <low bookshelf>(37)",
            "[movetowards] <beer glass>(53)",
            "[movetowards] <kitchen>(2)",
        ],
    );
    s.act(DOG, "[movetowards] <basket>(23)");
    s.expect_actions(
        DOG,
        &[
            "[putinto] <cookbook>(28) into <basket>(23)",
            "[movetowards] <coffee table>(4)",
            "[movetowards] <chair>(5)",
            "[movetowards] <chair>(6)",
            "[movetowards] <door>(24)",
            "[movetowards] <door>(35)",
            "[movetowards] <low bookshelf>(36)",
            "[movetowards] <low bookshelf>(37)",
            "[movetowards] <beer glass>(53)",
            "[movetowards] <kitchen>(2)",
        ],
    );
    s.act(DOG, "[putinto] <cookbook>(28) into <basket>(23)");
    s.expect_seen_edges(
        DOG,
        &[(28, "INSIDE", 23), (21, "CLOSE", 23), (21, "CLOSE", 28)],
    );
    s.expect_actions(
        DOG,
        &[
            "[grab] <cookbook>(28)",
            "[movetowards] <coffee table>(4)",
            "[movetowards] <chair>(5)",
            "[movetowards] <chair>(6)",
            "[movetowards] <door>(24)",
            "[movetowards] <door>(35)",
            "[movetowards] <low bookshelf>(36)",
            "[movetowards] <low bookshelf>(37)",
            "[movetowards] <beer glass>(53)",
            "[movetowards] <kitchen>(2)",
        ],
    );

    // Take-off: basket and cookbook out of the dog's reach.
    s.act(QUAD, "[takeoff_from] <livingroom floor>(1)");
    s.expect_high(&[23, 28], true);
    s.expect_view(DOG, LIVINGROOM_7);
    s.expect_unseen_edges(DOG, &[(21, "CLOSE", 23), (21, "CLOSE", 28), (23, "ON", 1)]);
    s.expect_actions(
        DOG,
        &[
            "[movetowards] <coffee table>(4)",
            "[movetowards] <chair>(5)",
            "[movetowards] <chair>(6)",
            "[movetowards] <door>(24)",
            "[movetowards] <door>(35)",
            "[movetowards] <low bookshelf>(36)",
            "[movetowards] <low bookshelf>(37)",
            "[movetowards] <beer glass>(53)",
            "[movetowards] <kitchen>(2)",
        ],
    );
    s.refused(DOG, "[grab] <cookbook>(28)", Reason::TooHigh);
    // Nothing else in the livingroom is LANDABLE.
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <livingroom floor>(1)",
            "[movetowards] <kitchen>(2)",
        ],
    );

    // Into the kitchen: above its floor, with the basket and the cookbook.
    s.act(QUAD, "[movetowards] <kitchen>(2)");
    let mut kitchen = KITCHEN_7.to_vec();
    kitchen.extend([22, 23, 28]);
    s.expect_view(QUAD, &kitchen);
    let mut edges = KITCHEN_7_EDGES.to_vec();
    edges.extend([
        (22, "ABOVE", 3),
        (22, "INSIDE", 2),
        (22, "WITH", 23),
        (28, "INSIDE", 23),
    ]);
    s.expect_edges(QUAD, &edges);
    s.expect_view(ARM, &kitchen);
    s.expect_view(DOG, &[0, 1, 2, 4, 5, 6, 21, 24, 34, 35, 36, 37, 53]);
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <kitchen floor>(3)",
            "[movetowards] <dining table>(9)",
            "[movetowards] <kitchen table>(11)",
            "[movetowards] <livingroom>(0)",
        ],
    );
    s.refused(QUAD, "[land_on] <dining table>(9)", Reason::NotAbove);
    s.refused(QUAD, "[land_on] <burner>(10)", Reason::NotLandable);

    s.act(QUAD, "[movetowards] <kitchen table>(11)");
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <kitchen table>(11)",
            "[movetowards] <kitchen floor>(3)",
            "[movetowards] <dining table>(9)",
            "[movetowards] <livingroom>(0)",
        ],
    );
    // Landing on the HIGH_HEIGHT kitchen table completes the task.
    let out = s.act(QUAD, "[land_on] <kitchen table>(11)");
    assert!(out.done);
    s.expect_high(&[23, 28], true);
    s.expect_actions(QUAD, &["[takeoff_from] <kitchen table>(11)"]);
    s.expect_seen_edges(ARM, &[(22, "ON", 11), (23, "ON", 11), (28, "INSIDE", 23)]);
    // The basket is ON the arm's table: the arm reaches the cookbook in it.
    s.expect_actions(
        ARM,
        &["[grab] <tomato sauce jar>(18)", "[grab] <cookbook>(28)"],
    );
    s.expect_actions(ARM_DINING, &["[grab] <fruit bowl>(30)"]);

    // The arm adds the tomato sauce jar to the landed basket.
    s.act(ARM, "[grab] <tomato sauce jar>(18)");
    s.expect_actions(
        ARM,
        &[
            "[puton] <tomato sauce jar>(18) on <kitchen table>(11)",
            "[putinto] <tomato sauce jar>(18) into <sink>(8)",
            "[puton] <tomato sauce jar>(18) on <burner>(10)",
            "[putinto] <tomato sauce jar>(18) into <basket>(23)",
        ],
    );
    let out = s.act(ARM, "[putinto] <tomato sauce jar>(18) into <basket>(23)");
    assert!(out.done);
    s.expect_seen_edges(QUAD, &[(18, "INSIDE", 23), (28, "INSIDE", 23)]);
    s.expect_unseen_edges(QUAD, &[(18, "ON", 11), (20, "HOLD", 18)]);
    s.expect_high(&[18], true);
    s.expect_actions(
        ARM,
        &["[grab] <tomato sauce jar>(18)", "[grab] <cookbook>(28)"],
    );
}

#[test]
fn the_dog_opens_the_closed_utility_room_door_and_carries_the_beer_glass_through_it() {
    let mut s = TASK7.clone();
    s.refused(DOG, "[movetowards] <utility room>(34)", Reason::DoorClosed);
    s.refused(DOG, "[open] <door>(35)", Reason::NotClose);

    s.act(DOG, "[movetowards] <door>(35)");
    s.expect_seen_edges(DOG, &[(21, "CLOSE", 35)]);
    s.expect_actions(
        DOG,
        &[
            "[open] <door>(35)",
            "[movetowards] <coffee table>(4)",
            "[movetowards] <chair>(5)",
            "[movetowards] <chair>(6)",
            "[movetowards] <basket>(23)",
            "[movetowards] <door>(24)",
            "[movetowards] <cookbook>(28)",
            "[movetowards] <low bookshelf>(36)",
            "[movetowards] <low bookshelf>(37)",
            "[movetowards] <beer glass>(53)",
            "[movetowards] <kitchen>(2)",
        ],
    );
    s.refused(ARM, "[open] <door>(24)", Reason::NotOpenable);
    s.act(DOG, "[open] <door>(35)");
    assert_eq!(s.states(35), ["OPEN"]);
    s.expect_actions(
        DOG,
        &[
            "[close] <door>(35)",
            "[movetowards] <coffee table>(4)",
            "[movetowards] <chair>(5)",
            "[movetowards] <chair>(6)",
            "[movetowards] <basket>(23)",
            "[movetowards] <door>(24)",
            "[movetowards] <cookbook>(28)",
            "[movetowards] <low bookshelf>(36)",
            "[movetowards] <low bookshelf>(37)",
            "[movetowards] <beer glass>(53)",
            "[movetowards] <kitchen>(2)",
            "[movetowards] <utility room>(34)",
        ],
    );

    // Fetch the beer glass from the coffee table.
    s.act(DOG, "[movetowards] <coffee table>(4)");
    s.expect_seen_edges(DOG, &[(21, "CLOSE", 4), (21, "CLOSE", 53)]);
    s.expect_actions(
        DOG,
        &[
            "[grab] <beer glass>(53)",
            "[movetowards] <chair>(5)",
            "[movetowards] <chair>(6)",
            "[movetowards] <basket>(23)",
            "[movetowards] <door>(24)",
            "[movetowards] <cookbook>(28)",
            "[movetowards] <door>(35)",
            "[movetowards] <low bookshelf>(36)",
            "[movetowards] <low bookshelf>(37)",
            "[movetowards] <kitchen>(2)",
            "[movetowards] <utility room>(34)",
        ],
    );
    s.act(DOG, "[grab] <beer glass>(53)");
    s.expect_actions(
        DOG,
        &[
            "[puton] <beer glass>(53) on <coffee table>(4)",
            "[movetowards] <chair>(5)",
            "[movetowards] <chair>(6)",
            "[movetowards] <basket>(23)",
            "[movetowards] <door>(24)",
            "[movetowards] <cookbook>(28)",
            "[movetowards] <door>(35)",
            "[movetowards] <low bookshelf>(36)",
            "[movetowards] <low bookshelf>(37)",
            "[movetowards] <kitchen>(2)",
            "[movetowards] <utility room>(34)",
        ],
    );

    // Through the open door, glass in hand.
    s.act(DOG, "[movetowards] <utility room>(34)");
    s.expect_view(DOG, &[0, 2, 21, 34, 35, 38, 39, 45, 53]);
    s.expect_edges(
        DOG,
        &[
            (21, "ON", 45),
            (21, "INSIDE", 34),
            (21, "HOLD", 53),
            (35, "LEADING TO", 0),
            (35, "LEADING TO", 34),
            (38, "ON", 45),
            (39, "ON", 45),
            (45, "INSIDE", 34),
        ],
    );
    s.expect_actions(
        DOG,
        &[
            "[movetowards] <door>(35)",
            "[movetowards] <storage shelf>(38)",
            "[movetowards] <packing box>(39)",
            "[movetowards] <livingroom>(0)",
        ],
    );
    s.act(DOG, "[movetowards] <packing box>(39)");
    s.expect_edges(
        DOG,
        &[
            (21, "ON", 45),
            (21, "INSIDE", 34),
            (21, "HOLD", 53),
            (21, "CLOSE", 39),
            (35, "LEADING TO", 0),
            (35, "LEADING TO", 34),
            (38, "ON", 45),
            (39, "ON", 45),
            (45, "INSIDE", 34),
        ],
    );
    s.expect_actions(
        DOG,
        &[
            "[putinto] <beer glass>(53) into <packing box>(39)",
            "[movetowards] <door>(35)",
            "[movetowards] <storage shelf>(38)",
            "[movetowards] <livingroom>(0)",
        ],
    );
    s.act(DOG, "[putinto] <beer glass>(53) into <packing box>(39)");
    s.expect_seen_edges(
        DOG,
        &[(53, "INSIDE", 39), (21, "CLOSE", 53), (21, "CLOSE", 39)],
    );
    s.expect_high(&[53], false);
    s.expect_actions(
        DOG,
        &[
            "[grab] <beer glass>(53)",
            "[movetowards] <door>(35)",
            "[movetowards] <storage shelf>(38)",
            "[movetowards] <livingroom>(0)",
        ],
    );

    // The dog has left: the livingroom holds only the quadrotor now. Flying, it may go
    // to both neighbouring rooms.
    s.expect_view(QUAD, &[0, 1, 2, 4, 5, 6, 22, 23, 24, 28, 34, 35, 36, 37]);
    s.act(QUAD, "[takeoff_from] <livingroom floor>(1)");
    s.expect_actions(
        QUAD,
        &[
            "[land_on] <livingroom floor>(1)",
            "[movetowards] <kitchen>(2)",
            "[movetowards] <utility room>(34)",
        ],
    );
}

#[test]
fn an_open_forever_door_offers_neither_open_nor_close_and_each_refusal_gives_its_reason() {
    let mut s = TASK7.clone();
    s.refused(DOG, "[grab] <cookbook>(28)", Reason::NotClose);
    s.refused(
        ARM_DINING,
        "[grab] <tomato sauce jar>(18)",
        Reason::OutOfReach,
    );
    s.refused(DOG, "[movetowards] <livingroom>(0)", Reason::AlreadyThere);

    s.act(DOG, "[movetowards] <door>(24)");
    // OPEN_FOREVER: neither open nor close is offered.
    s.expect_actions(
        DOG,
        &[
            "[movetowards] <coffee table>(4)",
            "[movetowards] <chair>(5)",
            "[movetowards] <chair>(6)",
            "[movetowards] <basket>(23)",
            "[movetowards] <cookbook>(28)",
            "[movetowards] <door>(35)",
            "[movetowards] <low bookshelf>(36)",
            "[movetowards] <low bookshelf>(37)",
            "[movetowards] <beer glass>(53)",
            "[movetowards] <kitchen>(2)",
        ],
    );
    s.refused(DOG, "[close] <door>(24)", Reason::AlwaysOpen);
    s.refused(DOG, "[open] <door>(24)", Reason::AlreadyOpen);
}
