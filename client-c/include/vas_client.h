/*
 * vas_client.h: the C interface of the vas client library (libvas_client.so, libvas_client.a).
 * Generated from client-c/src by cbindgen; do not edit (client-c/tests/header.rs says how to
 * regenerate it).
 *
 * A renderer or input device on the same machine as a vas server links this library: it reads
 * the scene's meshes and the verified poses of every part and hand segment, and sends tracker,
 * glove or hand-joints samples, over iceoryx2 shared memory.
 *
 * The loop of a renderer (client-c/examples/renderer.c is a whole one):
 *
 *     VasClient *client = NULL;
 *     if (vas_client_connect("demo", VAS_ROLE_RENDER, true, &client) != VAS_STATUS_OK) {
 *         fprintf(stderr, "%s
", vas_last_error_message());
 *     }
 *     for (;;) {
 *         VasWake wake;
 *         vas_client_wait(client, 1000, &wake);      // or a time-out of 0 in an engine's frame
 *         if (wake == VAS_WAKE_TERMINATED) break;
 *         vas_client_poll(client, NULL);
 *         const VasGeometry *geometry;               // upload when its generation changes
 *         vas_client_geometry(client, &geometry);
 *         VasPartsFrameHeader header; const VasPartState *parts; size_t part_count;
 *         vas_client_latest_parts(client, &header, &parts, &part_count);
 *         const VasHandFrame *hands; size_t hand_count;
 *         vas_client_latest_hands(client, &hands, &hand_count);
 *         // draw geometry->parts[parts[i].id] at parts[i].position, .rotation, and each
 *         // hand's segment mesh s at hands[h].segments[s]: no kinematics in the renderer.
 *     }
 *     vas_client_free(client);
 *
 * Errors. Every function that can fail returns a VasStatus: VAS_STATUS_OK, VAS_STATUS_EMPTY
 * (nothing of that kind has arrived yet: no error), or a negative code whose words
 * vas_last_error_message() gives for the calling thread. A null pointer or an out-of-range code
 * is an error, never a crash; a panic inside the library is VAS_STATUS_PANIC, never an unwind
 * into C (build the library with panic = "unwind", the default).
 *
 * Ownership. A VasClient is the caller's, from vas_client_connect to vas_client_free. Every
 * pointer the library hands out (frames, events, meshes, scene info, names) belongs to the
 * library: never free it; its function says until when it stays valid. Copy what must live
 * longer. Strings are NUL-terminated UTF-8. The library keeps no pointer the caller passes in.
 *
 * Threads. A client belongs to the thread that connected it (its iceoryx2 ports do): a call
 * from another thread returns VAS_STATUS_WRONG_THREAD. Clients on different threads are
 * independent.
 *
 * Waiting in an engine's loop. vas_client_wait sleeps on an iceoryx2 WaitSet over one listener
 * per output service. An engine with its own loop waits on those listeners' file descriptors
 * instead: vas_client_wake_descriptors gives them (one per output service); register them all
 * with poll, epoll or select (or an Unreal FRunnable's or a Unity thread's wait) and call
 * vas_client_poll when one is readable, which quiets them until the server publishes again.
 * Poll once after connecting, for the frames already queued. On Windows there are none
 * (VAS_STATUS_UNSUPPORTED): call vas_client_wait with a time-out of 0 once per rendered frame.
 *
 * Coordinates. vas is right-handed, z up, in metres; rotations are unit quaternions
 * (x, y, z, w). Unity is left-handed, y up, in metres: a vas point (x, y, z) is Unity's
 * (x, z, y), a vas rotation (qx, qy, qz, qw) is Unity's (-qx, -qz, -qy, qw). Unreal is
 * left-handed, z up, x forward, y right, in centimetres: a vas point is Unreal's
 * 100 * (x, -y, z), a rotation (-qx, qy, -qz, qw). The vas_pose_to_* and vas_point_to_*
 * functions and their *_from_* inverses do this. Both conversions are mirror images, so they
 * also reverse the winding of every triangle: swap two indices of each triangle (or draw both
 * sides, which CAD polygon soups need anyway). Normals convert as points do, without the scale.
 */

#ifndef VAS_CLIENT_H
#define VAS_CLIENT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/**
 * Role bit: the control service only (scene info, reset, loads, metaphor). Every client has it.
 */
#define VAS_ROLE_CONTROL 0

/**
 * Role bit: reads the server's output (geometry, parts, hands, events, force): a renderer.
 */
#define VAS_ROLE_RENDER 1

/**
 * Role bit: sends tracker, glove and hand-joints samples: an input device.
 */
#define VAS_ROLE_INPUT 2

/**
 * Every role: renders and sends.
 */
#define VAS_ROLE_ALL (VAS_ROLE_RENDER | VAS_ROLE_INPUT)

/**
 * Events a client keeps for `vas_client_take_events`; beyond this the oldest
 * are dropped (and counted), so that a program that never takes them does not grow without end.
 */
#define VAS_EVENT_CAPACITY 4096

/**
 * Flex angles of a glove sample and a hand frame (CyberGlove order).
 */
#define VAS_FLEX_COUNT 22

/**
 * Segments of a hand frame and of a hand's geometry (`vas_hand_segment_name` names them).
 */
#define VAS_HAND_SEGMENT_COUNT 16

/**
 * OpenXR joints of a hand-joints sample.
 */
#define VAS_HAND_JOINT_COUNT 26

/**
 * `VasPartState::flags` bit: a hand holds the part.
 */
#define VAS_PART_GRASPED (1 << 0)

/**
 * `VasPartState::flags` bit: the part touches another part or a hand.
 */
#define VAS_PART_TOUCHING (1 << 1)

/**
 * `VasPartState::flags` bit: the part slides along a contact.
 */
#define VAS_PART_SLIDING (1 << 2)

/**
 * `VasPartState::flags` bit: a hand pushes the part without holding it.
 */
#define VAS_PART_PUSHED (1 << 3)

/**
 * `VasSimEvent::other` when the other side of a contact is a hand, not a part.
 */
#define VAS_HAND_PART_ID UINT32_MAX

/**
 * `VasJointLocation::flags` bit: the orientation is valid.
 */
#define VAS_JOINT_ORIENTATION_VALID (1 << 0)

/**
 * `VasJointLocation::flags` bit: the position is valid.
 */
#define VAS_JOINT_POSITION_VALID (1 << 1)

/**
 * `VasJointLocation::flags` bit: the orientation is tracked, not inferred.
 */
#define VAS_JOINT_ORIENTATION_TRACKED (1 << 2)

/**
 * `VasJointLocation::flags` bit: the position is tracked, not inferred.
 */
#define VAS_JOINT_POSITION_TRACKED (1 << 3)

/**
 * Hand side code (`VasHandFrame::hand`, `VasSimEvent::hand`, ...): the right hand.
 */
#define VAS_HAND_RIGHT 0

/**
 * Hand side code: the left hand.
 */
#define VAS_HAND_LEFT 1

/**
 * Sliding metaphor code: the position is pulled towards the hand's ghost.
 */
#define VAS_METAPHOR_RUBBER_BAND 1

/**
 * Sliding metaphor code: position and orientation are both pulled towards the ghost.
 */
#define VAS_METAPHOR_SPIRAL_SPRING 2

/**
 * Sliding metaphor code: the part repeats the ghost's motion increment.
 */
#define VAS_METAPHOR_INCREMENTAL 3

/**
 * What a call of this library returned: [`VasStatus::Ok`] or [`VasStatus::Empty`] on success,
 * a negative code on an error, whose words [`vas_last_error_message`] gives.
 */
typedef enum {
  /**
   * Done.
   */
  VAS_STATUS_OK = 0,
  /**
   * Done, but there is nothing to give yet: no frame of that kind (or no geometry) has arrived
   * since the client connected. The out-parameters are left as they were.
   */
  VAS_STATUS_EMPTY = 1,
  /**
   * A pointer argument that must not be null was null.
   */
  VAS_STATUS_NULL_ARGUMENT = -1,
  /**
   * An argument is out of its range: an unknown role, side or metaphor code, a string that
   * is not UTF-8 or too long.
   */
  VAS_STATUS_INVALID_ARGUMENT = -2,
  /**
   * The client was used on another thread than the one that connected it (its iceoryx2
   * ports belong to that thread).
   */
  VAS_STATUS_WRONG_THREAD = -3,
  /**
   * The client lacks the role the call needs (render for frames, input for samples).
   */
  VAS_STATUS_MISSING_ROLE = -4,
  /**
   * The server's services have no room for another client of this role.
   */
  VAS_STATUS_FULL = -5,
  /**
   * No answer within the time-out: no server on this prefix, or it is stuck.
   */
  VAS_STATUS_TIMEOUT = -6,
  /**
   * The server refused a control request (an unknown scene name, a load while loading).
   */
  VAS_STATUS_REFUSED = -7,
  /**
   * The server sent something this library cannot read (a newer or corrupt peer).
   */
  VAS_STATUS_PROTOCOL = -8,
  /**
   * iceoryx2 failed: the prefix, a service or a port could not be opened or used.
   */
  VAS_STATUS_IPC = -9,
  /**
   * The library panicked: a bug. The client that was called should be freed.
   */
  VAS_STATUS_PANIC = -10,
  /**
   * This system lacks what the call needs (file descriptors, on Windows).
   */
  VAS_STATUS_UNSUPPORTED = -11,
} VasStatus;

/**
 * How a [`vas_client_wait`] ended.
 */
typedef enum {
  /**
   * New output is ready: call [`vas_client_poll`].
   */
  VAS_WAKE_READY = 0,
  /**
   * The time-out passed without new output.
   */
  VAS_WAKE_TIMEOUT = 1,
  /**
   * SIGINT or SIGTERM arrived (only when the client was connected with
   * `handle_termination_signals`): the program should end.
   */
  VAS_WAKE_TERMINATED = 2,
} VasWake;

/**
 * A connection to a vas server, opaque to C: made by [`vas_client_connect`], freed by
 * [`vas_client_free`]. It also keeps what the C side reads through pointers (events, the
 * geometry's and the scene's views), so that those pointers stay valid for as long as the header
 * says.
 */
typedef struct VasClient VasClient;

/**
 * How many frames of each kind a [`vas_client_poll`] received.
 */
typedef struct {
  /**
   * Parts frames.
   */
  size_t parts;
  /**
   * Hand frames (of every hand).
   */
  size_t hands;
  /**
   * Events.
   */
  size_t events;
  /**
   * Force frames.
   */
  size_t force;
  /**
   * Clearance frames.
   */
  size_t clearance;
  /**
   * Geometry generations.
   */
  size_t geometry;
} VasReceived;

/**
 * A rigid pose: position in metres and a unit quaternion `[x, y, z, w]`.
 */
typedef struct {
  /**
   * Position in metres.
   */
  double position[3];
  /**
   * Rotation as a unit quaternion in x, y, z, w order.
   */
  double rotation[4];
} VasWirePose;

/**
 * One part of the scene, as the control service describes it.
 */
typedef struct {
  /**
   * The id of the part in parts frames and geometry.
   */
  uint32_t id;
  /**
   * Whether a hand can grasp and move it.
   */
  bool movable;
  /**
   * Whether a name or path was cut to fit the wire.
   */
  bool truncated;
  /**
   * The part's name, NUL-terminated UTF-8.
   */
  const char *name;
  /**
   * Its collision group, NUL-terminated UTF-8.
   */
  const char *group;
  /**
   * The mesh file the server resolved, or a procedural shape's description.
   */
  const char *mesh_source;
  /**
   * Its pose when the scene was loaded.
   */
  VasWirePose initial_pose;
  /**
   * The scale applied to its mesh (the geometry's meshes have it applied already).
   */
  double scale;
} VasPartInfo;

/**
 * One hand of the scene.
 */
typedef struct {
  /**
   * Which hand, a `VAS_HAND_*` code.
   */
  uint32_t side;
  /**
   * Whose hand: an index into `VasSceneInfo::users`.
   */
  uint32_t user;
  /**
   * The hand model's name, NUL-terminated UTF-8.
   */
  const char *model;
} VasHandInfo;

/**
 * Counters of the server's input validation, since it started.
 */
typedef struct {
  /**
   * Tracker samples accepted.
   */
  uint64_t tracker_accepted;
  /**
   * Tracker samples rejected for a NaN or infinite value.
   */
  uint64_t tracker_rejected_non_finite;
  /**
   * Tracker samples rejected for a rotation that is not a unit quaternion.
   */
  uint64_t tracker_rejected_quaternion;
  /**
   * Glove samples accepted (clamped or not).
   */
  uint64_t glove_accepted;
  /**
   * Glove samples rejected for a NaN or infinite value.
   */
  uint64_t glove_rejected_non_finite;
  /**
   * Accepted glove samples with at least one value clamped into the joint limits.
   */
  uint64_t glove_samples_clamped;
  /**
   * Flex values clamped into the joint limits, over all glove samples.
   */
  uint64_t glove_values_clamped;
  /**
   * Tracker samples rejected for a position beyond [`MAX_POSITION_M`](crate::MAX_POSITION_M).
   */
  uint64_t tracker_rejected_out_of_range;
  /**
   * Hand-joints samples accepted and retargeted onto their hand.
   */
  uint64_t joints_accepted;
  /**
   * Hand-joints samples that say their hand is not tracked (a joint the retargeting needs is
   * not valid): not rejected, the hand stays where it was and its frames say it is untracked.
   */
  uint64_t joints_untracked;
  /**
   * Hand-joints samples rejected for a NaN or infinite position or radius.
   */
  uint64_t joints_rejected_non_finite;
  /**
   * Hand-joints samples rejected for an orientation that is not a unit quaternion.
   */
  uint64_t joints_rejected_quaternion;
  /**
   * Hand-joints samples rejected for a position beyond
   * [`MAX_POSITION_M`](crate::MAX_POSITION_M).
   */
  uint64_t joints_rejected_out_of_range;
  /**
   * Hand-joints samples rejected as no hand: joints out of anatomical order, or bones of
   * impossible length.
   */
  uint64_t joints_rejected_anatomy;
  /**
   * Hand-joints samples rejected for naming a side the scene has no hand for (or no side).
   */
  uint64_t joints_rejected_no_such_hand;
  /**
   * Samples of any stream rejected for a timestamp more than
   * [`MAX_TIMESTAMP_AHEAD_NS`](crate::MAX_TIMESTAMP_AHEAD_NS) beyond the server's clock.
   */
  uint64_t rejected_ahead;
  /**
   * Samples of any stream rejected for naming a user the scene does not have.
   */
  uint64_t rejected_no_such_user;
  /**
   * Tracker and glove samples rejected for naming a side their user has no hand for (or no
   * side).
   */
  uint64_t rejected_no_such_hand;
} VasInputStats;

/**
 * The server's scene: its name, parts, hands and generation.
 */
typedef struct {
  /**
   * The scene's name, NUL-terminated UTF-8.
   */
  const char *name;
  /**
   * The file the server loaded it from, NUL-terminated UTF-8.
   */
  const char *source;
  /**
   * The scene generation, the same number as its geometry's.
   */
  uint64_t generation;
  /**
   * `part_count` parts, indexed by id.
   */
  const VasPartInfo *parts;
  /**
   * Parts.
   */
  size_t part_count;
  /**
   * `hand_count` hands.
   */
  const VasHandInfo *hands;
  /**
   * Hands.
   */
  size_t hand_count;
  /**
   * The world's up direction (vas: z up).
   */
  double up[3];
  /**
   * Metres per unit of every length (vas: 1).
   */
  double metres_per_unit;
  /**
   * How many scenes the server offers to load by name.
   */
  uint32_t scenes_offered;
  /**
   * The sliding metaphor in use, a `VAS_METAPHOR_*` code: the scene's own, or the one a
   * client set since the last load or reset.
   */
  uint32_t metaphor;
  /**
   * The server's input counters at the time of the answer.
   */
  VasInputStats stats;
  /**
   * `user_count` users' names, NUL-terminated UTF-8, by the index that samples, frames,
   * events and hands name them with.
   */
  const char *const *users;
  /**
   * Users: 1 for a scene of one user (named "user" unless the scene names its users).
   */
  size_t user_count;
} VasSceneInfo;

/**
 * The sequence number and timestamp of one input sample; all zero before the first sample.
 */
typedef struct {
  /**
   * The sample's sequence number (0: no sample yet).
   */
  uint64_t seq;
  /**
   * The sample's timestamp in nanoseconds since the Unix epoch.
   */
  uint64_t timestamp_ns;
} VasInputStamp;

/**
 * User header of a `vas/output/parts` sample; the payload is a slice of [`PartState`].
 */
typedef struct {
  /**
   * Frame number of the parts stream, from 1.
   */
  uint64_t frame;
  /**
   * The latest tracker sample taken into account.
   */
  VasInputStamp tracker;
  /**
   * The latest glove sample taken into account.
   */
  VasInputStamp glove;
  /**
   * The latest hand-joints sample taken into account.
   */
  VasInputStamp joints;
  /**
   * When the frame was published, in nanoseconds since the Unix epoch.
   */
  uint64_t timestamp_ns;
  /**
   * Number of parts in the payload slice.
   */
  uint32_t part_count;
} VasPartsFrameHeader;

/**
 * The valid pose and state of one part.
 */
typedef struct {
  /**
   * The part's id: its index in the scene (see the control service's part info).
   */
  uint32_t id;
  /**
   * State bits: [`PART_GRASPED`], [`PART_TOUCHING`], [`PART_SLIDING`], [`PART_PUSHED`].
   */
  uint32_t flags;
  /**
   * Position in metres.
   */
  double position[3];
  /**
   * Rotation as a unit quaternion in x, y, z, w order.
   */
  double rotation[4];
} VasPartState;

/**
 * One hand as the collision loop verified it: root pose, flex vector, each segment's pose,
 * touching segments and grasp type.
 */
typedef struct {
  /**
   * Frame number of the hand stream, from 1.
   */
  uint64_t frame;
  /**
   * The tracker sample this frame answers (or the latest one, when it answers another
   * stream's sample).
   */
  VasInputStamp tracker;
  /**
   * The glove sample this frame answers (or the latest one, when it answers another
   * stream's sample).
   */
  VasInputStamp glove;
  /**
   * The hand-joints sample of this hand this frame answers (or the latest one, when it
   * answers another stream's sample).
   */
  VasInputStamp joints;
  /**
   * When the frame was published, in nanoseconds since the Unix epoch.
   */
  uint64_t timestamp_ns;
  /**
   * Pose of the hand root in the world (the tracker's cart pose times its hand pose).
   */
  VasWirePose root;
  /**
   * Joint angles in radians, CyberGlove order.
   */
  float flex[VAS_FLEX_COUNT];
  /**
   * Bit [`HandSegment::bit`] set: that segment touches a part.
   */
  uint32_t touching;
  /**
   * The recognised grasp, a [`GraspType`] code.
   */
  uint32_t grasp_type;
  /**
   * The hand, a [`HandSide`] code.
   */
  uint32_t hand;
  /**
   * 1 when the hand follows its input; 0 when its tracking is lost (it stays where it was).
   */
  uint32_t tracked;
  /**
   * Segments with a pose in [`HandFrame::segments`]: [`HAND_SEGMENT_COUNT`] with a hand
   * model, 0 in a scene without one.
   */
  uint32_t segment_count;
  /**
   * The user whose hand it is, an index into the scene's users
   * ([`ControlResponse::users`](crate::ControlResponse::users)).
   */
  uint32_t user;
  /**
   * Each segment's verified pose in the world, in [`HandSegment`] order: where a renderer
   * places the segment's mesh from `vas/scene/geometry`.
   */
  VasWirePose segments[VAS_HAND_SEGMENT_COUNT];
} VasHandFrame;

/**
 * Force and torque a force-feedback device should render, on `vas/output/force`.
 */
typedef struct {
  /**
   * Number of the hand frame the force belongs to.
   */
  uint64_t frame;
  /**
   * The tracker sample the force answers.
   */
  VasInputStamp tracker;
  /**
   * The glove sample the force answers.
   */
  VasInputStamp glove;
  /**
   * The hand-joints sample the force answers.
   */
  VasInputStamp joints;
  /**
   * When the frame was published, in nanoseconds since the Unix epoch.
   */
  uint64_t timestamp_ns;
  /**
   * Force on the hand root in newtons, world frame.
   */
  double force[3];
  /**
   * Torque about the hand root in newton metres, world frame.
   */
  double torque[3];
  /**
   * The hand whose held part pulls, a [`HandSide`] code.
   */
  uint32_t hand;
  /**
   * The user whose hand `hand` is, an index into the scene's users
   * ([`ControlResponse::users`](crate::ControlResponse::users)).
   */
  uint32_t user;
} VasForceFrame;

/**
 * A discrete simulation event on `vas/output/events`.
 */
typedef struct {
  /**
   * Number of the hand frame during which the event happened.
   */
  uint64_t frame;
  /**
   * The tracker sample that led to the event.
   */
  VasInputStamp tracker;
  /**
   * The glove sample that led to the event.
   */
  VasInputStamp glove;
  /**
   * The hand-joints sample that led to the event.
   */
  VasInputStamp joints;
  /**
   * When the event was published, in nanoseconds since the Unix epoch.
   */
  uint64_t timestamp_ns;
  /**
   * An [`EventKind`] code.
   */
  uint32_t kind;
  /**
   * A [`GraspType`] code for grasp events, 0 otherwise.
   */
  uint32_t grasp_type;
  /**
   * The part the event is about.
   */
  uint32_t part;
  /**
   * The other part of a contact or clearance, or [`HAND_PART_ID`].
   */
  uint32_t other;
  /**
   * The hand the event is about (grasp, release, hand-over, a contact with the hand) or whose
   * held part touched, a [`HandSide`] code; 0 for clearance events.
   */
  uint32_t hand;
  /**
   * The hand segment of a contact with the hand, a [`HandSegment`] code; 0 otherwise.
   */
  uint32_t segment;
  /**
   * The user whose hand `hand` is, an index into the scene's users
   * ([`ControlResponse::users`](crate::ControlResponse::users)); 0 for clearance events.
   */
  uint32_t user;
  /**
   * Padding, 0.
   */
  uint32_t reserved;
  /**
   * Contacts: where the two touch; clearances: the closest point on `part`. In the world
   * (metres); zero for other events.
   */
  double point[3];
  /**
   * Contacts: the unit normal at `point`, pointing from `other` towards `part`; zero for other
   * events.
   */
  double normal[3];
  /**
   * Clearances: the closest point on `other`, in the world (metres); zero for other events.
   */
  double other_point[3];
  /**
   * Clearances: the distance between `part` and `other` (metres); zero for other events.
   */
  double distance;
} VasSimEvent;

/**
 * One triangle mesh: a part's in the part's own frame (its scale applied), or a hand segment's
 * in the segment's frame. Every pointer stays valid as long as the [`VasGeometry`] it came in.
 */
typedef struct {
  /**
   * The part's or segment's name, NUL-terminated UTF-8.
   */
  const char *name;
  /**
   * `vertex_count` positions in metres, x, y, z each.
   */
  const float (*positions)[3];
  /**
   * `vertex_count` unit normals, one per position; null when the server sent none (compute
   * them).
   */
  const float (*normals)[3];
  /**
   * Vertices.
   */
  size_t vertex_count;
  /**
   * `triangle_count` triangles, three vertex indices each. CAD meshes may be polygon soups
   * whose winding means nothing: draw both sides.
   */
  const uint32_t (*triangles)[3];
  /**
   * Triangles.
   */
  size_t triangle_count;
} VasMesh;

/**
 * One hand's segment meshes, in segment order (`vas_hand_segment_name` names them).
 */
typedef struct {
  /**
   * Which hand, a `VAS_HAND_*` code.
   */
  uint32_t side;
  /**
   * Whose hand: an index into `VasSceneInfo::users`.
   */
  uint32_t user;
  /**
   * The hand model's name, NUL-terminated UTF-8.
   */
  const char *model;
  /**
   * `segment_count` meshes.
   */
  const VasMesh *segments;
  /**
   * Segments.
   */
  size_t segment_count;
} VasHandGeometry;

/**
 * Every mesh of one scene generation: parts by id, then each hand's segments.
 */
typedef struct {
  /**
   * The scene generation: one more after every load or reset of the scene.
   */
  uint64_t generation;
  /**
   * `part_count` meshes, indexed by part id.
   */
  const VasMesh *parts;
  /**
   * Parts.
   */
  size_t part_count;
  /**
   * `hand_count` hands.
   */
  const VasHandGeometry *hands;
  /**
   * Hands.
   */
  size_t hand_count;
} VasGeometry;

/**
 * One 6-DOF tracker report of one user's hand: the hand root and that user's cart (navigation)
 * pose.
 */
typedef struct {
  /**
   * Sender's sequence number, from 1, increasing by one per sample.
   */
  uint64_t seq;
  /**
   * When the sample was taken, in nanoseconds since the Unix epoch.
   */
  uint64_t timestamp_ns;
  /**
   * Pose of the hand root (the tracker on the back of the hand) in the cart's frame, i.e. in
   * tracking space.
   */
  VasWirePose hand;
  /**
   * Pose of the cart in the world: the navigation frame that carries the tracking space (and
   * with it the hand) through the scene. The hand root in the world is `cart * hand`.
   */
  VasWirePose cart;
  /**
   * Which tracker sent the sample (the VRPN sensor number).
   */
  uint32_t sensor_id;
  /**
   * The user whose hand it tracks: see [`HandJointsSample::user`].
   */
  uint32_t user;
  /**
   * Which of the user's hands, a [`HandSide`](crate::HandSide) code (0, right, when a
   * recording made before users names none).
   */
  uint32_t side;
  /**
   * Padding, 0 (not in recordings).
   */
  uint32_t reserved;
} VasTrackerSample;

/**
 * One glove report of one user's hand: the 22 calibrated joint angles.
 */
typedef struct {
  /**
   * Sender's sequence number, from 1, increasing by one per sample.
   */
  uint64_t seq;
  /**
   * When the sample was taken, in nanoseconds since the Unix epoch.
   */
  uint64_t timestamp_ns;
  /**
   * Joint angles in radians, in CyberGlove order ([`FLEX_JOINT_NAMES`]).
   */
  float flex[VAS_FLEX_COUNT];
  /**
   * The user whose hand wears the glove: see [`HandJointsSample::user`].
   */
  uint32_t user;
  /**
   * Which of the user's hands, a [`HandSide`](crate::HandSide) code (0, right, when a
   * recording made before users names none).
   */
  uint32_t side;
} VasGloveSample;

/**
 * One hand joint's location, as OpenXR's `XrHandJointLocationEXT` gives it.
 */
typedef struct {
  /**
   * Position in metres, in tracking space (the cart's frame).
   */
  double position[3];
  /**
   * Orientation as a unit quaternion in x, y, z, w order; the joint frame is OpenXR's: `-Z`
   * along the bone toward the fingertip, `+Y` on the back of the hand.
   */
  double rotation[4];
  /**
   * Distance from the joint to the skin, in metres (OpenXR's radius is a `float`).
   */
  float radius;
  /**
   * Which of position and orientation are valid and tracked: the `JOINT_*` bits, OpenXR's
   * `XrSpaceLocationFlags`.
   */
  uint32_t flags;
} VasJointLocation;

/**
 * One hand's tracked joints: OpenXR's 26 in OpenXR order, each with its pose, radius and
 * validity flags, and which hand it is.
 *
 * The order is `XrHandJointEXT`'s: palm 0, wrist 1, thumb metacarpal, proximal, distal, tip
 * 2-5, then index, middle, ring and little finger each metacarpal, proximal, intermediate,
 * distal, tip (6-10, 11-15, 16-20, 21-25).
 *
 * WebXR's `XRHand` has the same joints without the palm (25, wrist first). A WebXR producer
 * sends its joints at indices 1-25 and the palm with `flags` 0: OpenXR's own way of saying
 * that a joint's location is unknown. No separate "WebXR" mode is needed, because the server
 * uses no palm (the hand's root comes from the wrist and the fingers from their own joints);
 * a producer that has a palm simply sends it.
 */
typedef struct {
  /**
   * Sender's sequence number, from 1, increasing by one per sample.
   */
  uint64_t seq;
  /**
   * When the sample was taken, in nanoseconds since the Unix epoch.
   */
  uint64_t timestamp_ns;
  /**
   * The joints, in OpenXR order.
   */
  VasJointLocation joints[VAS_HAND_JOINT_COUNT];
  /**
   * Which hand, a [`HandSide`](crate::HandSide) code.
   */
  uint32_t side;
  /**
   * The user whose hand it is: an index into the scene's users, as the control service
   * lists them ([`ControlResponse::users`](crate::ControlResponse::users)); 0 in a scene
   * of one user.
   *
   * An index rather than the user's name: four bytes in a sample sent at the tracking rate,
   * compared without text, and a sender learns its index once from the scene info (names
   * are for people; the control response carries them). A scene's users keep their indices
   * until another scene is loaded, whose info a sender reads anyway.
   */
  uint32_t user;
} VasHandJointsSample;





#ifdef __cplusplus
extern "C" {
#endif // __cplusplus

/**
 * Connects to the vas server on `prefix` (its `--prefix`; null for the iceoryx2
 * configuration's default) with `roles` (`VAS_ROLE_*` bits combined with `|`).
 *
 * With `handle_termination_signals`, iceoryx2 catches SIGINT and SIGTERM and
 * [`vas_client_wait`] reports [`VasWake::Terminated`]; without, the application's own handling
 * stays in place. On success `*client` is a new handle that the caller owns and frees with
 * [`vas_client_free`]; it must be used on the calling thread only. On an error `*client` is
 * left unchanged.
 *
 * # Safety
 * `prefix` is null or a NUL-terminated string; `client` points to writable memory for a
 * pointer.
 */
VasStatus vas_client_connect(const char *prefix,
                             uint32_t roles,
                             bool handle_termination_signals,
                             VasClient **client);

/**
 * Closes the connection and frees the handle and everything it handed out (frames, geometry,
 * events, scene info). Null is allowed and does nothing. The handle must not be used again.
 * On another thread than the one that connected, nothing is freed (the ports cannot be closed
 * there) and the thread's last error says so.
 *
 * # Safety
 * `client` is null or a handle from [`vas_client_connect`] not freed yet.
 */
void vas_client_free(VasClient *client);

/**
 * Takes `roles` as well (`VAS_ROLE_*` bits), opening the ports of those the client lacks: e.g.
 * a renderer that starts forwarding a headset's hand joints takes [`VAS_ROLE_INPUT`]. On an
 * error the client keeps the roles it had.
 *
 * # Safety
 * `client` is a live handle from [`vas_client_connect`].
 */
VasStatus vas_client_take_roles(VasClient *client, uint32_t roles);

/**
 * Blocks until output is ready to be polled, `timeout_ms` milliseconds pass (`UINT64_MAX`:
 * no end), or a handled termination signal arrives; `*wake` says which. Output that arrived
 * before the call counts: nothing is missed between a poll and the next wait. Needs the render
 * role.
 *
 * An engine with its own loop calls it with a time-out of 0 once per frame, or waits on
 * `vas_client_wake_descriptors` in that loop instead.
 *
 * # Safety
 * `client` is a live handle from [`vas_client_connect`]; `wake` points to a writable
 * [`VasWake`].
 */
VasStatus vas_client_wait(VasClient *client, uint64_t timeout_ms, VasWake *wake);

/**
 * Receives every queued output frame without blocking: the newest geometry, parts frame, hand
 * frames and force frame are kept for their accessors, events for
 * `vas_client_take_events`. `*received` (when not null) counts what came.
 * Needs the render role.
 *
 * A poll ends the validity of the parts and hand pointers handed out before it, and quiets the
 * `vas_client_wake_descriptors` until the server publishes again.
 *
 * # Safety
 * `client` is a live handle from [`vas_client_connect`]; `received` is null or points to a
 * writable [`VasReceived`].
 */
VasStatus vas_client_poll(VasClient *client, VasReceived *received);

/**
 * Asks the server for its scene and waits up to `timeout_ms` for the whole answer: `*scene`
 * points to the description.
 *
 * Everything behind `*scene` belongs to the client and stays valid until the next call of this
 * function or `vas_client_free`.
 *
 * # Safety
 * `client` is a live handle; `scene` points to writable memory for a pointer.
 */
VasStatus vas_client_scene_info(VasClient *client, uint64_t timeout_ms, const VasSceneInfo **scene);

/**
 * Asks the server to put the scene back to its initial state, and waits up to `timeout_ms` for
 * its answer. A new geometry generation follows.
 *
 * # Safety
 * `client` is a live handle.
 */
VasStatus vas_client_reset(VasClient *client, uint64_t timeout_ms);

/**
 * Asks the server to load the scene it offers as `name` (NUL-terminated UTF-8; `vas-client
 * scenes` lists them), and waits up to `timeout_ms` for its answer: [`VasStatus::Refused`] for a
 * name it does not offer. A new geometry generation follows.
 *
 * # Safety
 * `client` is a live handle; `name` is a NUL-terminated string.
 */
VasStatus vas_client_load_named_scene(VasClient *client, const char *name, uint64_t timeout_ms);

/**
 * Asks the server to slide grasped parts with `metaphor` (a `VAS_METAPHOR_*` code), and waits
 * up to `timeout_ms` for its answer.
 *
 * # Safety
 * `client` is a live handle.
 */
VasStatus vas_client_set_metaphor(VasClient *client, uint32_t metaphor, uint64_t timeout_ms);

/**
 * Converts a pose of vas (metres, right-handed, z up) into Unity's (metres, left-handed, y up):
 * position `(x, z, y)`, rotation `(−qx, −qz, −qy, qw)`. `to` may be `from`.
 *
 * # Safety
 * `from` points to a readable pose, `to` to a writable one.
 */
VasStatus vas_pose_to_unity(const VasWirePose *from, VasWirePose *to);

/**
 * Converts a pose of Unity into vas's: the inverse of [`vas_pose_to_unity`] (the same swaps).
 *
 * # Safety
 * `from` points to a readable pose, `to` to a writable one.
 */
VasStatus vas_pose_from_unity(const VasWirePose *from, VasWirePose *to);

/**
 * Converts a pose of vas into Unreal's (centimetres, left-handed, z up, x forward, y right):
 * position `100 (x, −y, z)`, rotation `(−qx, qy, −qz, qw)`. `to` may be `from`.
 *
 * # Safety
 * `from` points to a readable pose, `to` to a writable one.
 */
VasStatus vas_pose_to_unreal(const VasWirePose *from, VasWirePose *to);

/**
 * Converts a pose of Unreal into vas's: the inverse of [`vas_pose_to_unreal`].
 *
 * # Safety
 * `from` points to a readable pose, `to` to a writable one.
 */
VasStatus vas_pose_from_unreal(const VasWirePose *from, VasWirePose *to);

/**
 * Converts a point of vas (3 doubles, metres) into Unity's: `(x, z, y)`. Normals and
 * directions convert the same way. `to` may be `from`.
 *
 * # Safety
 * `from` points to 3 readable doubles, `to` to 3 writable ones.
 */
VasStatus vas_point_to_unity(const double (*from)[3], double (*to)[3]);

/**
 * Converts a point of Unity into vas's: the inverse of [`vas_point_to_unity`].
 *
 * # Safety
 * `from` points to 3 readable doubles, `to` to 3 writable ones.
 */
VasStatus vas_point_from_unity(const double (*from)[3], double (*to)[3]);

/**
 * Converts a point of vas (metres) into Unreal's (centimetres): `100 (x, −y, z)`. A direction
 * or normal converts as `(x, −y, z)`, without the scale. `to` may be `from`.
 *
 * # Safety
 * `from` points to 3 readable doubles, `to` to 3 writable ones.
 */
VasStatus vas_point_to_unreal(const double (*from)[3], double (*to)[3]);

/**
 * Converts a point of Unreal (centimetres) into vas's (metres): the inverse of
 * [`vas_point_to_unreal`].
 *
 * # Safety
 * `from` points to 3 readable doubles, `to` to 3 writable ones.
 */
VasStatus vas_point_from_unreal(const double (*from)[3], double (*to)[3]);

/**
 * Writes the file descriptors of the client's wake-up listeners, one per output service, to
 * `fds` (room for `capacity`) and their number to `*count`. Each becomes readable when the
 * server publishes on its service: register them all with poll, epoll or select (or an engine's
 * run loop: an Unreal `FRunnable`, a Unity thread) and call `vas_client_poll` when one is.
 * The poll empties them, so they stay quiet until the server publishes again; one that wakes
 * with nothing new to poll is harmless. Poll once after connecting: the frames a new client
 * finds queued do not make them readable. Needs the render role.
 *
 * A null `fds` with a `capacity` of 0 asks for their number only. With a `capacity` smaller
 * than their number, `*count` gets the number, `fds` is left alone and the status is
 * `VAS_STATUS_INVALID_ARGUMENT`.
 *
 * The descriptors belong to the client: never read, write or close them; they stay valid
 * until `vas_client_free`. Where the system has no file descriptors (Windows), the status is
 * `VAS_STATUS_UNSUPPORTED`: use `vas_client_wait` there.
 *
 * # Safety
 * `client` is a live handle from `vas_client_connect`; `fds` is null or points to `capacity`
 * writable `int`s; `count` points to a writable `size_t`.
 */
VasStatus vas_client_wake_descriptors(VasClient *client, int *fds, size_t capacity, size_t *count);

/**
 * The newest parts frame: `*header` gets a copy of its header, `*parts` and `*count` the pose
 * and state of every part, indexed by part id. [`VasStatus::Empty`] before the first parts
 * frame.
 *
 * `*parts` belongs to the client and stays valid until the next `vas_client_poll`
 * or `vas_client_free`.
 *
 * # Safety
 * `client` is a live handle; `header`, `parts` and `count` point to writable memory of their
 * types.
 */
VasStatus vas_client_latest_parts(VasClient *client,
                                  VasPartsFrameHeader *header,
                                  const VasPartState **parts,
                                  size_t *count);

/**
 * The newest frame of every hand of the scene, right hand first: `*hands` and `*count` (0
 * before the first hand frame, which is no error). Each frame carries its side
 * (`VasHandFrame::hand`, a `VAS_HAND_*` code) and each segment's verified world pose, where
 * the segment's mesh of the geometry goes.
 *
 * `*hands` belongs to the client and stays valid until the next
 * `vas_client_poll` or `vas_client_free`.
 *
 * # Safety
 * `client` is a live handle; `hands` and `count` point to writable memory of their types.
 */
VasStatus vas_client_latest_hands(VasClient *client, const VasHandFrame **hands, size_t *count);

/**
 * A copy of the newest frame of user `user`'s hand on `side` (a `VAS_HAND_*` code) into
 * `*hand`; [`VasStatus::Empty`] before the first frame of that hand. `user` is the user's
 * index in the scene info's `users` (0 in a scene of one user).
 *
 * # Safety
 * `client` is a live handle; `hand` points to a writable `VasHandFrame`.
 */
VasStatus vas_client_latest_hand_of(VasClient *client,
                                    uint32_t user,
                                    uint32_t side,
                                    VasHandFrame *hand);

/**
 * A copy of the newest force frame (force and torque for a force-feedback device while a part
 * is held) into `*force`; [`VasStatus::Empty`] before the first.
 *
 * # Safety
 * `client` is a live handle; `force` points to a writable `VasForceFrame`.
 */
VasStatus vas_client_latest_force(VasClient *client, VasForceFrame *force);

/**
 * The events the polls received since the last take, oldest first (grasps, releases,
 * contacts, hand-overs, clearances): `*events` and `*count` (0 when none came). `*dropped`
 * (when not null) counts the events lost meanwhile because more than `VAS_EVENT_CAPACITY` were
 * waiting.
 *
 * `*events` belongs to the client and stays valid until the next take or
 * `vas_client_free`.
 *
 * # Safety
 * `client` is a live handle; `events` and `count` point to writable memory of their types;
 * `dropped` is null or points to a writable `uint64_t`.
 */
VasStatus vas_client_take_events(VasClient *client,
                                 const VasSimEvent **events,
                                 size_t *count,
                                 uint64_t *dropped);

/**
 * The newest scene geometry the polls received: `*geometry` points to every part's and hand
 * segment's mesh with the scene generation. [`VasStatus::Empty`] before the first geometry (a
 * client gets the current one soon after it connects; poll first).
 *
 * Everything behind `*geometry` belongs to the client and stays valid until a later call of
 * this function returns another generation (after a load or reset of the scene), or
 * `vas_client_free`: a renderer uploads the meshes when the generation
 * changes and may keep reading them until it asks again.
 *
 * # Safety
 * `client` is a live handle; `geometry` points to writable memory for a pointer.
 */
VasStatus vas_client_geometry(VasClient *client, const VasGeometry **geometry);

/**
 * Sends a tracker sample (hand root in the cart's frame, cart in the world) and wakes the
 * server. The sample is copied; needs the input role. The server checks it: a non-finite or
 * out-of-range value is rejected and counted there, not here.
 *
 * # Safety
 * `client` is a live handle; `sample` points to a readable `VasTrackerSample`.
 */
VasStatus vas_client_send_tracker(VasClient *client, const VasTrackerSample *sample);

/**
 * Sends a glove sample (22 flex angles in radians, CyberGlove order) and wakes the server. The
 * sample is copied; needs the input role.
 *
 * # Safety
 * `client` is a live handle; `sample` points to a readable `VasGloveSample`.
 */
VasStatus vas_client_send_glove(VasClient *client, const VasGloveSample *sample);

/**
 * Sends one hand's 26 OpenXR joints and wakes the server. The sample is copied; needs the
 * input role.
 *
 * # Safety
 * `client` is a live handle; `sample` points to a readable `VasHandJointsSample`.
 */
VasStatus vas_client_send_hand_joints(VasClient *client, const VasHandJointsSample *sample);

/**
 * Returns once the server has taken in every sample this client sent before the call (waiting
 * up to `timeout_ms`): a sent sample lives in the sender's shared memory until then, so a
 * program that sends and exits calls this before `vas_client_free`.
 *
 * # Safety
 * `client` is a live handle.
 */
VasStatus vas_client_flush_inputs(VasClient *client, uint64_t timeout_ms);

/**
 * The hand side `code` (a `VAS_HAND_*` code) in words: `right` or `left`. Null for an unknown
 * code. The string is static: never freed, never changed.
 */
const char *vas_hand_side_name(uint32_t code);

/**
 * The grasp type `code` (`VasHandFrame::grasp_type`, `VasSimEvent::grasp_type`) in words,
 * e.g. `power` or `tip_pinch`. Null for an unknown code. The string is static.
 */
const char *vas_grasp_type_name(uint32_t code);

/**
 * The event kind `code` (`VasSimEvent::kind`) in words, e.g. `grasp` or `contact_begin`.
 * Null for an unknown code. The string is static.
 */
const char *vas_event_kind_name(uint32_t code);

/**
 * The hand segment `index` (the order of `VasHandFrame::segments` and of a hand's segment
 * meshes; also the bit of `VasHandFrame::touching`) in words, e.g. `palm` or `index_distal`.
 * Null past the last segment. The string is static.
 */
const char *vas_hand_segment_name(uint32_t index);

/**
 * The words of the last error a call of this library returned on the calling thread, as a
 * NUL-terminated UTF-8 string; empty before the first error.
 *
 * The string belongs to the library: it stays valid until the next call that fails on this
 * thread. Copy it to keep it. Never null.
 */
const char *vas_last_error_message(void);

#ifdef __cplusplus
}  // extern "C"
#endif  // __cplusplus

#endif  /* VAS_CLIENT_H */
