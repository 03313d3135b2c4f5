// The C library of vas (vas_client.h) for C#: its codes, its structs laid out as C lays them
// out, and its functions bound with P/Invoke (Vas.Native). VasClient.cs wraps them safely; it
// needs nothing of Unity.

using System;
using System.Runtime.InteropServices;

namespace Vas
{
    /// <summary>What a call returned (VasStatus): Ok or Empty on success, negative on an error.</summary>
    public enum Status : int
    {
        Ok = 0,
        Empty = 1,
        NullArgument = -1,
        InvalidArgument = -2,
        WrongThread = -3,
        MissingRole = -4,
        Full = -5,
        Timeout = -6,
        Refused = -7,
        Protocol = -8,
        Ipc = -9,
        Panic = -10,
        Unsupported = -11,
    }

    /// <summary>How a wait ended (VasWake).</summary>
    public enum Wake : int
    {
        Ready = 0,
        Timeout = 1,
        Terminated = 2,
    }

    /// <summary>The roles of a client (VAS_ROLE_*): the ports it holds.</summary>
    [Flags]
    public enum Roles : uint
    {
        Control = 0,
        Render = 1,
        Input = 2,
        All = Render | Input,
    }

    /// <summary>Which hand (VAS_HAND_*).</summary>
    public enum HandSide : uint
    {
        Right = 0,
        Left = 1,
    }

    /// <summary>A point or direction in metres: [f64; 3].</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct Vec3
    {
        public double X, Y, Z;

        public Vec3(double x, double y, double z)
        {
            X = x;
            Y = y;
            Z = z;
        }
    }

    /// <summary>A unit quaternion in x, y, z, w order: [f64; 4].</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct Quat
    {
        public double X, Y, Z, W;

        public Quat(double x, double y, double z, double w)
        {
            X = x;
            Y = y;
            Z = z;
            W = w;
        }
    }

    /// <summary>A position and a rotation (VasWirePose).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct WirePose
    {
        public Vec3 Position;
        public Quat Rotation;
    }

    /// <summary>The sequence number and timestamp of one input sample (VasInputStamp).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct InputStamp
    {
        public ulong Seq;
        public ulong TimestampNs;
    }

    /// <summary>How many frames of each kind a poll received (VasReceived).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct Received
    {
        public UIntPtr Parts, Hands, Events, Force, Clearance, Geometry;
    }

    /// <summary>The header of a parts frame (VasPartsFrameHeader).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct PartsFrameHeader
    {
        public ulong Frame;
        public InputStamp Tracker, Glove, Joints;
        public ulong TimestampNs;
        public uint PartCount;
    }

    /// <summary>The pose and state of one part (VasPartState).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct PartState
    {
        public const uint Grasped = 1, Touching = 2, Sliding = 4, Pushed = 8;

        public uint Id;
        public uint Flags;
        public Vec3 Position;
        public Quat Rotation;

        public WirePose Pose
        {
            get { return new WirePose { Position = Position, Rotation = Rotation }; }
        }
    }

    /// <summary>One hand as the server verified it (VasHandFrame).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct HandFrame
    {
        public const int FlexCount = 22;
        public const int SegmentCount = 16;

        public ulong Frame;
        public InputStamp Tracker, Glove, Joints;
        public ulong TimestampNs;
        public WirePose Root;
        [MarshalAs(UnmanagedType.ByValArray, SizeConst = FlexCount)]
        public float[] Flex;
        public uint Touching;
        public uint GraspType;
        public uint Hand;
        public uint Tracked;
        public uint SegmentPoseCount;
        public uint User;
        [MarshalAs(UnmanagedType.ByValArray, SizeConst = SegmentCount)]
        public WirePose[] Segments;
    }

    /// <summary>A grasp, release, contact, hand-over, push or clearance event (VasSimEvent).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct SimEvent
    {
        public ulong Frame;
        public InputStamp Tracker, Glove, Joints;
        public ulong TimestampNs;
        public uint Kind, GraspType, Part, Other, Hand, Segment, User, Reserved;
        public Vec3 Point, Normal, OtherPoint;
        public double Distance;
    }

    /// <summary>The force and torque a force-feedback device renders (VasForceFrame).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct ForceFrame
    {
        public ulong Frame;
        public InputStamp Tracker, Glove, Joints;
        public ulong TimestampNs;
        public Vec3 Force, Torque;
        public uint Hand;
        public uint User;
    }

    /// <summary>A 6-DOF tracker sample (VasTrackerSample).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct TrackerSample
    {
        public ulong Seq;
        public ulong TimestampNs;
        public WirePose Hand;
        public WirePose Cart;
        public uint SensorId;
        public uint User;
        public HandSide Side;
        public uint Reserved;
    }

    /// <summary>A data glove's 22 flex values in radians (VasGloveSample).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct GloveSample
    {
        public ulong Seq;
        public ulong TimestampNs;
        [MarshalAs(UnmanagedType.ByValArray, SizeConst = HandFrame.FlexCount)]
        public float[] Flex;
        public uint User;
        public HandSide Side;
    }

    /// <summary>One tracked joint of a hand (VasJointLocation).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct JointLocation
    {
        public Vec3 Position;
        public Quat Rotation;
        public float Radius;
        public uint Flags;
    }

    /// <summary>One hand's 26 OpenXR joints (VasHandJointsSample).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct HandJointsSample
    {
        public const int JointCount = 26;

        public ulong Seq;
        public ulong TimestampNs;
        [MarshalAs(UnmanagedType.ByValArray, SizeConst = JointCount)]
        public JointLocation[] Joints;
        public uint Side;
        public uint User;
    }

    /// <summary>One mesh of the geometry as the library holds it (VasMesh).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct NativeMesh
    {
        public IntPtr Name;
        public IntPtr Positions;
        public IntPtr Normals;
        public UIntPtr VertexCount;
        public IntPtr Triangles;
        public UIntPtr TriangleCount;
    }

    /// <summary>One hand's segment meshes as the library holds them (VasHandGeometry).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct NativeHandGeometry
    {
        public uint Side;
        public uint User;
        public IntPtr Model;
        public IntPtr Segments;
        public UIntPtr SegmentCount;
    }

    /// <summary>Every mesh of a scene generation as the library holds it (VasGeometry).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct NativeGeometry
    {
        public ulong Generation;
        public IntPtr Parts;
        public UIntPtr PartCount;
        public IntPtr Hands;
        public UIntPtr HandCount;
    }

    /// <summary>The server's input counters (VasInputStats).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct InputStats
    {
        public ulong TrackerAccepted, TrackerRejectedNonFinite, TrackerRejectedQuaternion;
        public ulong GloveAccepted, GloveRejectedNonFinite, GloveSamplesClamped, GloveValuesClamped;
        public ulong TrackerRejectedOutOfRange;
        public ulong JointsAccepted, JointsUntracked, JointsRejectedNonFinite;
        public ulong JointsRejectedQuaternion, JointsRejectedOutOfRange, JointsRejectedAnatomy;
        public ulong JointsRejectedNoSuchHand;
        public ulong RejectedAhead;
        public ulong RejectedNoSuchUser, RejectedNoSuchHand;
    }

    /// <summary>One part of the scene as the library holds it (VasPartInfo).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct NativePartInfo
    {
        public uint Id;
        [MarshalAs(UnmanagedType.U1)]
        public bool Movable;
        [MarshalAs(UnmanagedType.U1)]
        public bool Truncated;
        public IntPtr Name;
        public IntPtr Group;
        public IntPtr MeshSource;
        public WirePose InitialPose;
        public double Scale;
    }

    /// <summary>One hand of the scene as the library holds it (VasHandInfo).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct NativeHandInfo
    {
        public uint Side;
        public uint User;
        public IntPtr Model;
    }

    /// <summary>The server's scene as the library holds it (VasSceneInfo).</summary>
    [StructLayout(LayoutKind.Sequential)]
    public struct NativeSceneInfo
    {
        public IntPtr Name;
        public IntPtr Source;
        public ulong Generation;
        public IntPtr Parts;
        public UIntPtr PartCount;
        public IntPtr Hands;
        public UIntPtr HandCount;
        public Vec3 Up;
        public double MetresPerUnit;
        public uint ScenesOffered;
        public uint Metaphor;
        public InputStats Stats;
        public IntPtr Users;
        public UIntPtr UserCount;
    }

    /// <summary>The library's functions. Every pointer's lifetime is the header's.</summary>
    public static class Native
    {
        public const string Library = "vas_client";

        [DllImport(Library)]
        public static extern IntPtr vas_last_error_message();

        [DllImport(Library)]
        public static extern Status vas_client_connect(byte[] prefix, Roles roles,
            [MarshalAs(UnmanagedType.U1)] bool handleTerminationSignals, out IntPtr client);

        [DllImport(Library)]
        public static extern void vas_client_free(IntPtr client);

        [DllImport(Library)]
        public static extern Status vas_client_take_roles(IntPtr client, Roles roles);

        [DllImport(Library)]
        public static extern Status vas_client_wait(IntPtr client, ulong timeoutMs, out Wake wake);

        [DllImport(Library)]
        public static extern Status vas_client_poll(IntPtr client, out Received received);

        [DllImport(Library)]
        public static extern Status vas_client_geometry(IntPtr client, out IntPtr geometry);

        [DllImport(Library)]
        public static extern Status vas_client_latest_parts(IntPtr client,
            out PartsFrameHeader header, out IntPtr parts, out UIntPtr count);

        [DllImport(Library)]
        public static extern Status vas_client_latest_hands(IntPtr client, out IntPtr hands,
            out UIntPtr count);

        [DllImport(Library)]
        public static extern Status vas_client_latest_hand_of(IntPtr client, uint user,
            HandSide side, out HandFrame hand);

        [DllImport(Library)]
        public static extern Status vas_client_latest_force(IntPtr client, out ForceFrame force);

        [DllImport(Library)]
        public static extern Status vas_client_take_events(IntPtr client, out IntPtr events,
            out UIntPtr count, out ulong dropped);

        [DllImport(Library)]
        public static extern Status vas_client_send_tracker(IntPtr client, ref TrackerSample sample);

        [DllImport(Library)]
        public static extern Status vas_client_send_glove(IntPtr client, ref GloveSample sample);

        [DllImport(Library)]
        public static extern Status vas_client_send_hand_joints(IntPtr client,
            ref HandJointsSample sample);

        [DllImport(Library)]
        public static extern Status vas_client_flush_inputs(IntPtr client, ulong timeoutMs);

        [DllImport(Library)]
        public static extern Status vas_client_scene_info(IntPtr client, ulong timeoutMs,
            out IntPtr scene);

        [DllImport(Library)]
        public static extern Status vas_client_reset(IntPtr client, ulong timeoutMs);

        [DllImport(Library)]
        public static extern Status vas_client_load_named_scene(IntPtr client, byte[] name,
            ulong timeoutMs);

        [DllImport(Library)]
        public static extern Status vas_client_set_metaphor(IntPtr client, uint metaphor,
            ulong timeoutMs);

        [DllImport(Library)]
        public static extern Status vas_pose_to_unity(ref WirePose from, out WirePose to);

        [DllImport(Library)]
        public static extern Status vas_pose_from_unity(ref WirePose from, out WirePose to);

        [DllImport(Library)]
        public static extern Status vas_pose_to_unreal(ref WirePose from, out WirePose to);

        [DllImport(Library)]
        public static extern Status vas_pose_from_unreal(ref WirePose from, out WirePose to);

        [DllImport(Library)]
        public static extern Status vas_point_to_unity(ref Vec3 from, out Vec3 to);

        [DllImport(Library)]
        public static extern Status vas_point_from_unity(ref Vec3 from, out Vec3 to);

        [DllImport(Library)]
        public static extern Status vas_point_to_unreal(ref Vec3 from, out Vec3 to);

        [DllImport(Library)]
        public static extern Status vas_point_from_unreal(ref Vec3 from, out Vec3 to);

        [DllImport(Library)]
        public static extern IntPtr vas_hand_side_name(uint code);

        [DllImport(Library)]
        public static extern IntPtr vas_grasp_type_name(uint code);

        [DllImport(Library)]
        public static extern IntPtr vas_event_kind_name(uint code);

        [DllImport(Library)]
        public static extern IntPtr vas_hand_segment_name(uint index);
    }
}
