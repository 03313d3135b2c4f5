//! A scene's human-readable summary, as `check-scene` prints it.

use std::fmt::Write as _;

use super::Scene;

impl Scene {
    /// A human-readable summary: parts, triangles, groups, parameters and rates.
    pub fn summary(&self) -> String {
        let mut s = String::new();
        let triangles = self.triangle_count();
        let _ = writeln!(s, "scene {:?} ({})", self.name, self.source.display());
        let _ = writeln!(
            s,
            "parts: {} ({} movable), {triangles} triangles",
            self.parts.len(),
            self.parts.iter().filter(|p| p.movable).count()
        );
        for (id, part) in self.parts.iter().enumerate() {
            let t = part.pose.translation.vector;
            let (roll, pitch, yaw) = part.pose.rotation.euler_angles();
            let _ = writeln!(
                s,
                "  {id:>3} {:<16} {:<7} group {:<10} {:>7} triangles  at [{:.4}, {:.4}, {:.4}] m, \
                 rpy [{:.1}, {:.1}, {:.1}]°  {}",
                part.name,
                if part.movable { "movable" } else { "static" },
                part.group,
                part.mesh.triangles().len(),
                t.x,
                t.y,
                t.z,
                // Adding zero turns -0.0 into 0.0 for display.
                roll.to_degrees() + 0.0,
                pitch.to_degrees() + 0.0,
                yaw.to_degrees() + 0.0,
                part.mesh_source
            );
        }
        let ignored: Vec<String> = self
            .groups
            .not_of_interest
            .iter()
            .map(|[a, b]| format!("{a}/{b}"))
            .collect();
        let _ = writeln!(
            s,
            "groups: {}; not of interest: {} (and every static/static pair)",
            self.groups.names.join(", "),
            if ignored.is_empty() {
                "none".to_owned()
            } else {
                ignored.join(", ")
            }
        );
        let (p, sl, cl) = (&self.params, &self.params.sliding, &self.params.clasp);
        let contact_tolerance = sl
            .contact_tolerance
            .map_or("1e-4 of the part's size".to_owned(), |t| format!("{t} m"));
        let clearance = match p.clearance.threshold {
            Some(threshold) => match p.clearance.parts {
                super::ClearanceParts::Held => format!("{threshold} m, held parts"),
                super::ClearanceParts::Movable => format!("{threshold} m, movable parts"),
            },
            None => "off".to_owned(),
        };
        let _ = writeln!(
            s,
            "params: {}-DOPs; sliding {} (contact tolerance {contact_tolerance}, lift {}, \
             {} iterations, {} stall cycles, cluster angle {} rad, {} slide-in units); \
             clasp (flex tolerance {} rad, root tolerance {} m, {} steps, max motion {} m); \
             tracking (lost after {} s, grace {} s); clearance {clearance}",
            p.dop_orientations,
            sl.metaphor,
            sl.lift,
            sl.max_iterations,
            sl.stall_cycles,
            sl.cluster_angle,
            sl.allowances.len(),
            cl.flex_tolerance,
            cl.root_tolerance,
            cl.max_steps,
            cl.max_motion,
            p.tracking.lost_after,
            p.tracking.grace
        );
        let r = &self.rates;
        let _ = writeln!(
            s,
            "rates: publish {} Hz, collision {} Hz, sliding {} Hz, grasping {} Hz",
            r.publish_hz, r.collision_hz, r.sliding_hz, r.grasping_hz
        );
        let hands: Vec<String> = (self.hands.iter())
            .map(|hand| {
                let user = self
                    .users
                    .get(hand.user as usize)
                    .map_or("?", String::as_str);
                format!("{} ({user})", hand.path.display())
            })
            .collect();
        let _ = write!(
            s,
            "hands: {}",
            if hands.is_empty() {
                "none".to_owned()
            } else {
                hands.join(", ")
            }
        );
        s
    }
}
