// A Unity renderer of vas: a component that draws every part and hand segment the server
// publishes, as children of its GameObject, and moves them each frame. Only inside Unity: the
// rest of the sample compiles without it.
#if UNITY_5_3_OR_NEWER
using System.Collections.Generic;
using UnityEngine;

namespace Vas
{
    /// <summary>Connects on Start, builds a GameObject with a mesh for every part and hand
    /// segment of each scene generation, and on every Update moves them to the newest poses,
    /// converted to Unity's frame by the library (vas_pose_to_unity).</summary>
    public sealed class VasRenderer : MonoBehaviour
    {
        /// <summary>The server's --prefix; empty for the default.</summary>
        public string Prefix = "";
        public Material PartMaterial;
        public Material HandMaterial;

        private Client client;
        private ulong? generation;
        private readonly List<GameObject> drawn = new List<GameObject>();
        private readonly List<Transform> parts = new List<Transform>();
        // Keyed by user and side: every user's hands are drawn.
        private readonly Dictionary<(uint, uint), Transform[]> handSegments =
            new Dictionary<(uint, uint), Transform[]>();

        private void Start()
        {
            client = Client.Connect(string.IsNullOrEmpty(Prefix) ? null : Prefix, Roles.Render, false);
        }

        private void Update()
        {
            if (client == null)
            {
                return;
            }
            // Unity's loop is the wait: take whatever arrived since the last frame.
            client.Poll();
            ulong? latest = client.GeometryGeneration();
            if (latest == null)
            {
                return; // Nothing to draw before the meshes.
            }
            if (latest != generation)
            {
                Rebuild(client.Geometry());
            }
            PartsFrame frame = client.LatestParts();
            if (frame != null)
            {
                foreach (PartState part in frame.Parts)
                {
                    if (part.Id < parts.Count)
                    {
                        Place(parts[(int)part.Id], part.Pose);
                    }
                }
            }
            foreach (HandFrame hand in client.LatestHands())
            {
                Transform[] segments;
                if (!handSegments.TryGetValue((hand.User, hand.Hand), out segments))
                {
                    continue;
                }
                int count = Mathf.Min((int)hand.SegmentPoseCount, segments.Length);
                for (int i = 0; i < count; i++)
                {
                    // Where the server verified the segment: no kinematics here.
                    Place(segments[i], hand.Segments[i]);
                }
            }
        }

        private void OnDestroy()
        {
            if (client != null)
            {
                client.Dispose();
                client = null;
            }
        }

        /// <summary>Replaces the drawn objects with those of a new scene generation.</summary>
        private void Rebuild(SceneGeometry geometry)
        {
            foreach (GameObject old in drawn)
            {
                Destroy(old);
            }
            drawn.Clear();
            parts.Clear();
            handSegments.Clear();
            generation = geometry.Generation;
            foreach (MeshData mesh in geometry.Parts)
            {
                parts.Add(Build(mesh, PartMaterial));
            }
            foreach (HandMeshes hand in geometry.Hands)
            {
                handSegments[(hand.User, (uint)hand.Side)] =
                    System.Array.ConvertAll(hand.Segments, mesh => Build(mesh, HandMaterial));
            }
        }

        /// <summary>A child object drawing `mesh`, its vertices converted to Unity's frame.</summary>
        private Transform Build(MeshData mesh, Material material)
        {
            GameObject shown = new GameObject(mesh.Name);
            shown.transform.SetParent(transform, false);
            drawn.Add(shown);
            int count = mesh.Positions.Length / 3;
            Vector3[] vertices = new Vector3[count];
            for (int i = 0; i < count; i++)
            {
                vertices[i] = ToVector(mesh.Positions, i);
            }
            // The conversion is a reflection: swapping two indices of each triangle keeps its
            // outside facing out under back-face culling.
            int[] triangles = (int[])mesh.Triangles.Clone();
            for (int i = 0; i + 2 < triangles.Length; i += 3)
            {
                int swapped = triangles[i + 1];
                triangles[i + 1] = triangles[i + 2];
                triangles[i + 2] = swapped;
            }
            Mesh drawnMesh = new Mesh();
#if UNITY_2017_3_OR_NEWER
            if (count > 65535)
            {
                drawnMesh.indexFormat = UnityEngine.Rendering.IndexFormat.UInt32;
            }
#endif
            drawnMesh.vertices = vertices;
            drawnMesh.triangles = triangles;
            if (mesh.Normals != null)
            {
                Vector3[] normals = new Vector3[count];
                for (int i = 0; i < count; i++)
                {
                    normals[i] = ToVector(mesh.Normals, i);
                }
                drawnMesh.normals = normals;
            }
            else
            {
                drawnMesh.RecalculateNormals();
            }
            shown.AddComponent<MeshFilter>().sharedMesh = drawnMesh;
            shown.AddComponent<MeshRenderer>().sharedMaterial = material;
            return shown.transform;
        }

        /// <summary>Vertex `index` of an x, y, z run of vas, in Unity's frame.</summary>
        private static Vector3 ToVector(float[] run, int index)
        {
            Vec3 unity = UnityFrame.Point(new Vec3(run[3 * index], run[3 * index + 1], run[3 * index + 2]));
            return new Vector3((float)unity.X, (float)unity.Y, (float)unity.Z);
        }

        private static void Place(Transform shown, WirePose vas)
        {
            WirePose unity = UnityFrame.Pose(vas);
            shown.localPosition = new Vector3((float)unity.Position.X, (float)unity.Position.Y, (float)unity.Position.Z);
            shown.localRotation = new Quaternion((float)unity.Rotation.X, (float)unity.Rotation.Y,
                (float)unity.Rotation.Z, (float)unity.Rotation.W);
        }
    }
}
#endif
