// Vas.Client, a safe wrapper over the bindings of VasNative.cs: it owns a connection, turns
// status codes into exceptions and copies frames out of the library's memory. It needs nothing
// of Unity; VasRenderer.cs draws with it inside Unity.

using System;
using System.Runtime.InteropServices;
using System.Text;

namespace Vas
{
    /// <summary>A failed call: the library's status and its message.</summary>
    public sealed class VasException : Exception
    {
        public readonly Status Status;

        public VasException(Status status, string message) : base(message)
        {
            Status = status;
        }

        /// <summary>Throws for a failed `action`; otherwise whether there was something (Ok)
        /// rather than nothing yet (Empty).</summary>
        public static bool Check(Status status, string action)
        {
            if (status == Status.Ok || status == Status.Empty)
            {
                return status == Status.Ok;
            }
            string message = Text.Read(Native.vas_last_error_message());
            throw new VasException(status, "cannot " + action + ": " + message);
        }
    }

    /// <summary>One mesh, copied: positions and normals as x, y, z runs, triangles as index
    /// triples.</summary>
    public sealed class MeshData
    {
        public string Name;
        public float[] Positions;
        /// <summary>One per position, or null when the server sent none.</summary>
        public float[] Normals;
        public int[] Triangles;
    }

    /// <summary>One hand's segment meshes, in segment order.</summary>
    public sealed class HandMeshes
    {
        /// <summary>Whose hand: an index into the scene's users.</summary>
        public uint User;
        public HandSide Side;
        public string Model;
        public MeshData[] Segments;
    }

    /// <summary>Every mesh of one scene generation, copied.</summary>
    public sealed class SceneGeometry
    {
        public ulong Generation;
        /// <summary>Indexed by part id.</summary>
        public MeshData[] Parts;
        public HandMeshes[] Hands;
    }

    /// <summary>A parts frame, copied.</summary>
    public sealed class PartsFrame
    {
        public PartsFrameHeader Header;
        /// <summary>Indexed by part id.</summary>
        public PartState[] Parts;
    }

    /// <summary>Strings and arrays between the library's memory and C#.</summary>
    public static class Text
    {
        /// <summary>A NUL-terminated UTF-8 string of the library; null for a null pointer.</summary>
        public static string Read(IntPtr text)
        {
            if (text == IntPtr.Zero)
            {
                return null;
            }
            int length = 0;
            while (Marshal.ReadByte(text, length) != 0)
            {
                length++;
            }
            byte[] bytes = new byte[length];
            Marshal.Copy(text, bytes, 0, length);
            return Encoding.UTF8.GetString(bytes);
        }

        /// <summary>`text` as a NUL-terminated UTF-8 string for the library; null for null.</summary>
        public static byte[] Terminated(string text)
        {
            return text == null ? null : Encoding.UTF8.GetBytes(text + "\0");
        }

        /// <summary>`count` structs of the library at `first`, copied.</summary>
        public static T[] Structs<T>(IntPtr first, UIntPtr count) where T : struct
        {
            T[] items = new T[checked((int)count.ToUInt64())];
            int size = Marshal.SizeOf(typeof(T));
            for (int i = 0; i < items.Length; i++)
            {
                items[i] = (T)Marshal.PtrToStructure(IntPtr.Add(first, i * size), typeof(T));
            }
            return items;
        }
    }

    /// <summary>The names of the wire's codes; null for a code the library does not know.</summary>
    public static class Names
    {
        public static string HandSide(uint code) { return Text.Read(Native.vas_hand_side_name(code)); }
        public static string GraspType(uint code) { return Text.Read(Native.vas_grasp_type_name(code)); }
        public static string EventKind(uint code) { return Text.Read(Native.vas_event_kind_name(code)); }
        public static string HandSegment(uint index) { return Text.Read(Native.vas_hand_segment_name(index)); }
    }

    /// <summary>Poses and points of vas (right-handed, z up, metres) in Unity's frame
    /// (left-handed, y up, metres), by the library's conversion.</summary>
    public static class UnityFrame
    {
        public static WirePose Pose(WirePose vas)
        {
            WirePose unity;
            VasException.Check(Native.vas_pose_to_unity(ref vas, out unity), "convert a pose");
            return unity;
        }

        /// <summary>A point, or a direction (Unity's scale is vas's).</summary>
        public static Vec3 Point(Vec3 vas)
        {
            Vec3 unity;
            VasException.Check(Native.vas_point_to_unity(ref vas, out unity), "convert a point");
            return unity;
        }
    }

    /// <summary>A connection to a vas server. Use it, and dispose it, on the thread that
    /// connected it: the library refuses calls from other threads, so there is no finalizer.</summary>
    public sealed class Client : IDisposable
    {
        private IntPtr handle;

        private Client(IntPtr handle)
        {
            this.handle = handle;
        }

        /// <summary>Connects on `prefix` (the server's --prefix; null for the default).</summary>
        public static Client Connect(string prefix, Roles roles, bool handleTerminationSignals)
        {
            IntPtr handle;
            Status status = Native.vas_client_connect(Text.Terminated(prefix), roles,
                handleTerminationSignals, out handle);
            VasException.Check(status, "connect to the vas server");
            return new Client(handle);
        }

        public void Dispose()
        {
            Native.vas_client_free(handle);
            handle = IntPtr.Zero;
        }

        /// <summary>Blocks until output is ready to poll or `timeoutMs` pass.</summary>
        public Wake Wait(ulong timeoutMs)
        {
            Wake wake;
            VasException.Check(Native.vas_client_wait(Live(), timeoutMs, out wake), "wait");
            return wake;
        }

        /// <summary>Receives every queued frame without blocking.</summary>
        public Received Poll()
        {
            Received received;
            VasException.Check(Native.vas_client_poll(Live(), out received), "poll");
            return received;
        }

        /// <summary>The generation of the newest geometry, or null before the first: a
        /// renderer copies the meshes (Geometry) only when it changes.</summary>
        public ulong? GeometryGeneration()
        {
            IntPtr geometry;
            if (!VasException.Check(Native.vas_client_geometry(Live(), out geometry), "read the geometry"))
            {
                return null;
            }
            return ((NativeGeometry)Marshal.PtrToStructure(geometry, typeof(NativeGeometry))).Generation;
        }

        /// <summary>A copy of the newest geometry, or null before the first.</summary>
        public SceneGeometry Geometry()
        {
            IntPtr pointer;
            if (!VasException.Check(Native.vas_client_geometry(Live(), out pointer), "read the geometry"))
            {
                return null;
            }
            NativeGeometry geometry = (NativeGeometry)Marshal.PtrToStructure(pointer, typeof(NativeGeometry));
            NativeHandGeometry[] hands = Text.Structs<NativeHandGeometry>(geometry.Hands, geometry.HandCount);
            return new SceneGeometry
            {
                Generation = geometry.Generation,
                Parts = Array.ConvertAll(Text.Structs<NativeMesh>(geometry.Parts, geometry.PartCount), CopyMesh),
                Hands = Array.ConvertAll(hands, hand => new HandMeshes
                {
                    User = hand.User,
                    Side = (HandSide)hand.Side,
                    Model = Text.Read(hand.Model),
                    Segments = Array.ConvertAll(Text.Structs<NativeMesh>(hand.Segments, hand.SegmentCount), CopyMesh),
                }),
            };
        }

        /// <summary>A copy of the newest parts frame, or null before the first.</summary>
        public PartsFrame LatestParts()
        {
            PartsFrameHeader header;
            IntPtr parts;
            UIntPtr count;
            Status status = Native.vas_client_latest_parts(Live(), out header, out parts, out count);
            if (!VasException.Check(status, "read the parts frame"))
            {
                return null;
            }
            return new PartsFrame { Header = header, Parts = Text.Structs<PartState>(parts, count) };
        }

        /// <summary>Copies of the newest frame of every hand, right hand first.</summary>
        public HandFrame[] LatestHands()
        {
            IntPtr hands;
            UIntPtr count;
            VasException.Check(Native.vas_client_latest_hands(Live(), out hands, out count), "read the hand frames");
            return Text.Structs<HandFrame>(hands, count);
        }

        /// <summary>The events since the last take, oldest first; `dropped` counts those lost.</summary>
        public SimEvent[] TakeEvents(out ulong dropped)
        {
            IntPtr events;
            UIntPtr count;
            VasException.Check(Native.vas_client_take_events(Live(), out events, out count, out dropped), "take the events");
            return Text.Structs<SimEvent>(events, count);
        }

        public void Send(TrackerSample sample)
        {
            VasException.Check(Native.vas_client_send_tracker(Live(), ref sample), "send a tracker sample");
        }

        public void Send(GloveSample sample)
        {
            VasException.Check(Native.vas_client_send_glove(Live(), ref sample), "send a glove sample");
        }

        public void Send(HandJointsSample sample)
        {
            VasException.Check(Native.vas_client_send_hand_joints(Live(), ref sample), "send a hand-joints sample");
        }

        /// <summary>The scene's name, or throws when no server answers within `timeoutMs`.</summary>
        public string SceneName(ulong timeoutMs)
        {
            IntPtr scene;
            VasException.Check(Native.vas_client_scene_info(Live(), timeoutMs, out scene), "ask for the scene");
            return Text.Read(((NativeSceneInfo)Marshal.PtrToStructure(scene, typeof(NativeSceneInfo))).Name);
        }

        public void Reset(ulong timeoutMs)
        {
            VasException.Check(Native.vas_client_reset(Live(), timeoutMs), "reset the scene");
        }

        public void LoadNamedScene(string name, ulong timeoutMs)
        {
            VasException.Check(Native.vas_client_load_named_scene(Live(), Text.Terminated(name), timeoutMs), "load a scene");
        }

        /// <summary>The handle, or an error once disposed (the library would refuse null).</summary>
        private IntPtr Live()
        {
            if (handle == IntPtr.Zero)
            {
                throw new ObjectDisposedException("Vas.Client");
            }
            return handle;
        }

        private static MeshData CopyMesh(NativeMesh mesh)
        {
            int vertices = checked((int)mesh.VertexCount.ToUInt64());
            MeshData copy = new MeshData
            {
                Name = Text.Read(mesh.Name),
                Positions = new float[3 * vertices],
                Triangles = new int[checked(3 * (int)mesh.TriangleCount.ToUInt64())],
            };
            if (vertices == 0)
            {
                return copy;
            }
            Marshal.Copy(mesh.Positions, copy.Positions, 0, copy.Positions.Length);
            if (copy.Triangles.Length > 0)
            {
                Marshal.Copy(mesh.Triangles, copy.Triangles, 0, copy.Triangles.Length);
            }
            if (mesh.Normals != IntPtr.Zero)
            {
                copy.Normals = new float[3 * vertices];
                Marshal.Copy(mesh.Normals, copy.Normals, 0, copy.Normals.Length);
            }
            return copy;
        }
    }
}
