// A console program for the test suite: prints the size of every struct of VasNative.cs and the
// offset of its last field as C# lays them out for P/Invoke, then calls the built library
// (a pose converted to Unity's frame, a segment's name, a null handle refused) and prints what
// it answered. The suite compares the layouts with the library's own and checks the answers.

using System;
using System.Globalization;
using System.Runtime.InteropServices;
using Vas;

public static class LayoutCheck
{
    private static void Layout(Type type, string lastField)
    {
        Console.WriteLine("{0} size={1} {2}={3}", type.Name, Marshal.SizeOf(type), lastField,
            Marshal.OffsetOf(type, lastField));
    }

    private static string Number(double value)
    {
        return value.ToString("R", CultureInfo.InvariantCulture);
    }

    public static int Main()
    {
        Layout(typeof(Received), "Geometry");
        Layout(typeof(WirePose), "Rotation");
        Layout(typeof(InputStamp), "TimestampNs");
        Layout(typeof(PartsFrameHeader), "PartCount");
        Layout(typeof(PartState), "Rotation");
        Layout(typeof(HandFrame), "Segments");
        Layout(typeof(SimEvent), "Distance");
        Layout(typeof(ForceFrame), "User");
        Layout(typeof(TrackerSample), "Reserved");
        Layout(typeof(GloveSample), "Side");
        Layout(typeof(JointLocation), "Flags");
        Layout(typeof(HandJointsSample), "User");
        Layout(typeof(NativeMesh), "TriangleCount");
        Layout(typeof(NativeHandGeometry), "SegmentCount");
        Layout(typeof(NativeGeometry), "HandCount");
        Layout(typeof(InputStats), "RejectedNoSuchHand");
        Layout(typeof(NativePartInfo), "Scale");
        Layout(typeof(NativeHandInfo), "Model");
        Layout(typeof(NativeSceneInfo), "UserCount");

        // vas's point (1, 2, 3) turned 90 degrees about its z axis.
        double half = Math.Sqrt(0.5);
        WirePose pose = new WirePose
        {
            Position = new Vec3(1, 2, 3),
            Rotation = new Quat(0, 0, half, half),
        };
        WirePose unity = UnityFrame.Pose(pose);
        Console.WriteLine("unity position={0} {1} {2} rotation={3} {4} {5} {6}",
            Number(unity.Position.X), Number(unity.Position.Y), Number(unity.Position.Z),
            Number(unity.Rotation.X), Number(unity.Rotation.Y), Number(unity.Rotation.Z),
            Number(unity.Rotation.W));
        Console.WriteLine("segment 6 name={0}", Names.HandSegment(6));
        Wake wake;
        Status status = Native.vas_client_wait(IntPtr.Zero, 0, out wake);
        Console.WriteLine("null client status={0} message={1}", status,
            Text.Read(Native.vas_last_error_message()));
        return 0;
    }
}
