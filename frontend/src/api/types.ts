// Names for the generated schema types; nothing here is written by hand twice.
import type { components } from "./schema";

type S = components["schemas"];
export type MachineStatus = S["MachineStatus"];
export type MachineSummary = S["MachineSummary"];
export type SimulationStatus = S["SimulationStatus"];
export type AxisStatus = S["AxisStatus"];
export type AxisSignals = S["AxisSignals"];
export type PendingM = S["PendingM"];
export type JobError = S["JobErrorModel"];
export type Refusal = S["Refusal"];
export type ValidationIssue = S["ValidationIssue"];
export type ParameterProblem = S["ParameterProblem"];
export type ParameterValue = S["ParameterValue"];
export type ParameterDef = S["ParameterDef"];
export type ParameterChange = S["ParameterChange"];
export type ParameterWriteResult = S["ParameterWriteResult"];
export type VersionInfo = S["VersionInfo"];
export type VersionDiff = S["VersionDiff"];
export type ParamDiff = S["ParamDiff"];
export type CommandResult = S["CommandResult"];
export type HliUnit = S["HliCommand"]["unit"];
export type Hello = S["Hello"];
export type Subscribe = S["Subscribe"];
export type Subscribed = S["Subscribed"];
export type EventMessage = S["EventMessage"];
export type ErrorMessage = S["ErrorMessage"];
export type StatusMessage = S["StatusMessage"];
export type NoticeMessage = S["NoticeMessage"];
export type FrameHeader = S["FrameHeader"];
export type SignalInfo = S["SignalInfo"];
export type Command =
  | S["MdiCommand"]
  | S["SpindleCommand"]
  | S["SpindlePositionCommand"]
  | S["GearCommand"]
  | S["HomeCommand"]
  | S["JogCommand"]
  | S["MoveCommand"]
  | S["OverrideCommand"]
  | S["HliCommand"]
  | S["PlcModeCommand"]
  | S["PlcAckCommand"]
  | S["PlcSignalCommand"]
  | S["ResetCommand"]
  | S["ProgramLoadCommand"]
  | S["CycleStartCommand"]
  | S["FeedholdCommand"]
  | S["SingleBlockCommand"]
  | S["ProgramStopCommand"];
export type ChannelStatus = S["ChannelStatus"];
export type ProgramInfo = S["ProgramInfo"];
export type Program = S["Program"];
export type ProgramPreview = S["ProgramPreview"];
export type PreviewSegment = S["PreviewSegment"];
export type Scope = ParameterValue["scope"];
export type ScopeStatus = S["ScopeStatus"];
export type ScopeSetup = S["ScopeSetupModel"];
export type LevelTrigger = S["LevelTriggerModel"];
export type EventTrigger = S["EventTriggerModel"];
export type TraceInfo = S["TraceInfo"];
export type TraceDetail = S["TraceDetail"];
export type TraceCompare = S["TraceCompare"];
export type Measurements = S["MeasurementsModel"];
export type RecordingInfo = S["RecordingInfo"];
export type Me = S["Me"];
export type Role = S["Role"];
export type LoginRequest = S["LoginRequest"];
export type Action = S["Action"];
export type ControlState = S["ControlState"];
export type ControlParty = S["ControlParty"];
export type ControlAction = S["ControlAction"];
export type StaleValue = S["StaleValue"];
export type AuditRecord = S["AuditRecord"];
export type AuditPage = S["AuditPage"];
export type AuditKind = AuditRecord["kind"];
export type AuditVerification = S["AuditVerification"];
export type HistoryEntry = S["HistoryEntry"];
export type HistoryPage = S["HistoryPage"];
export type HistoryKind = HistoryEntry["kind"];
export type HistoryMessage = S["HistoryMessage"];
export type FlightRecorderStatus = S["FlightRecorderStatus"];
export type ShareLink = S["ShareLink"];
export type Fleet = S["Fleet"];
export type ShareCreated = S["ShareCreated"];
export type BundleInfo = S["BundleInfo"];
export type BundleDetail = S["BundleDetail"];
export type WsTicket = S["WsTicket"];
export type TokenInfo = S["TokenInfo"];
export type TokenCreate = S["TokenCreate"];
export type TokenCreated = S["TokenCreated"];
export type UserInfo = S["UserInfo"];
export type UserCreate = S["UserCreate"];
export type UserChange = S["UserChange"];
export type AssistantInfo = S["AssistantInfo"];
export type LoopGainRequest = S["LoopGainRequest"];
export type AssistResult = S["AssistResult"];
export type AssistChange = S["AssistChange"];
export type AssistSeries = S["AssistSeries"];
export type AssistRunInfo = S["AssistRunInfo"];
export type AssistRun = S["AssistRun"];
export type SignOff = S["SignOff"];
export type SignOffRequest = S["SignOffRequest"];
export type ResolutionRequest = S["ResolutionRequest"];
export type MultiGainCalcRequest = S["MultiGainCalcRequest"];
export type SpeedScalingRequest = S["SpeedScalingRequest"];
export type CurveFitRequest = S["CurveFitRequest"];
export type CurveRunUpRequest = S["CurveRunUpRequest"];
export type GearSelectionRequest = S["GearSelectionRequest"];
export type GearSelectionResult = S["GearSelectionResult"];
export type GearRangeValues = S["GearRangeValues"];
export type AssistProgress = S["AssistProgress"];
export type ExerciseInfo = S["ExerciseInfo"];
export type ClassInfo = S["ClassInfo"];
export type ClassCreate = S["ClassCreate"];
export type ClassCreated = S["ClassCreated"];
export type MachineLists = S["MachineLists"];
export type SeatInfo = S["SeatInfo"];
export type SeatLink = S["SeatLink"];
export type SeatDetail = S["SeatDetail"];
export type CheckState = S["CheckState"];
export type FindingState = S["FindingState"];
export type AnswerGiven = S["AnswerGiven"];
export type GridFrame = S["GridFrame"];
export type SeatFrame = S["SeatFrame"];
export type RaisedHand = S["RaisedHand"];
export type AxisLine = S["AxisLine"];
export type FaultInject = S["FaultInject"];
export type FaultInfo = S["FaultInfo"];
export type SeatFaults = S["SeatFaults"];
export type SnapshotInfo = S["SnapshotInfo"];
export type Exercise = S["Exercise"];
export type HintInfo = S["HintInfo"];
export type ServiceAxes = S["ServiceAxes"];
export type AxisService = S["AxisService"];
export type LimitInForce = S["LimitInForce"];
export type SeatResult = S["SeatResult"];
export type SeatReplay = S["SeatReplay"];
export type StageResult = S["StageResult"];
export type RosterStudent = S["RosterStudent"];
export type StudentRecord = S["StudentRecord"];
export type ExerciseDryRun = S["ExerciseDryRun"];
